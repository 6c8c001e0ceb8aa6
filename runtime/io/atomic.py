"""Atomic file writes: the one way kvrod writes a result file.

``with atomic_path(path) as tmp: write(tmp)`` writes under a temporary name in the same
folder (``.NAME.PID.tmp[SUFFIX]``) and renames it onto ``path`` at the end, so a reader
never sees half a file and a run that dies leaves the previous complete file. If writing
fails (disk full, a bug) the temporary file is removed, and an OSError without a file
name gets the destination's name, so the one-line error says which file. Ctrl-C or
SIGTERM during a write is delivered once the file is complete
(:func:`runtime.signals.held_signals`: an interrupt inside ``zipfile`` left the
archive's writer open, and ``np.savez`` then raised a ValueError instead; a second signal
stops the write at once).
"""

from __future__ import annotations

import contextlib
import errno
import os
from collections.abc import Iterator
from pathlib import Path

from runtime.signals import held_signals


@contextlib.contextmanager
def atomic_path(path: Path, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{suffix}")
    with held_signals():
        try:
            yield tmp
            tmp.replace(path)
        except BaseException as exc:
            with contextlib.suppress(OSError):
                tmp.unlink()
            if isinstance(exc, OSError) and exc.filename is None:
                raise OSError(exc.errno or errno.EIO, exc.strerror or str(exc),
                              str(path)) from exc
            raise


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_bytes(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


#: metadata written by matplotlib that changes between runs or installations (the software
#: version, creation dates), removed so that the same figure gives the same bytes
_VOLATILE_METADATA = {".png": {"Software": None},
                      ".pdf": {"Creator": None, "Producer": None, "CreationDate": None},
                      ".svg": {"Creator": None, "Date": None}}


def save_figure(fig, path: Path, **kwargs) -> Path:
    """``fig.savefig`` atomically (the temporary keeps the image suffix for matplotlib).

    Deterministic: the same figure gives the same bytes on every run (no software version
    or date in the file's metadata; a caller's ``metadata`` is merged over that). Pass a
    fixed ``dpi`` for the same pixel size everywhere.
    """
    path = Path(path)
    volatile = _VOLATILE_METADATA.get(path.suffix.lower())
    if volatile is not None:
        kwargs["metadata"] = {**volatile, **(kwargs.get("metadata") or {})}
    with atomic_path(path, suffix=path.suffix) as tmp:
        fig.savefig(tmp, **kwargs)
    return path

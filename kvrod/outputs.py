"""Results folders of the commands: checked before computing, locked while written.

Every command that writes a folder calls :func:`results_folder` before it computes
anything: the path is checked (not a file, writable, not too long), a folder that holds a
result (its marker file) is refused unless ``--overwrite``, and the folder is locked for
the command's lifetime (:mod:`runtime.io.folder`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Iterator
from pathlib import Path

from runtime.io import folder as F


@contextlib.contextmanager
def results_folder(out: Path, command: str, *, markers: Iterable[str], overwrite: bool,
                   names: Iterable[str], patterns: Iterable[str] = ("*.png", ".*.tmp")
                   ) -> Iterator[Path]:
    """Check, refuse-or-overwrite and lock ``out`` for ``kvrod COMMAND``; yields the path.

    ``markers``: the files whose presence means "this folder holds a result";
    ``names``/``patterns``: what the command writes (removed by ``overwrite``).
    """
    out = Path(out)
    F.check_output_path(out)
    F.refuse_existing(out, command, tuple(markers), overwrite=overwrite)
    with F.claim(out, command, overwrite=overwrite, names=names, patterns=patterns) as c:
        yield out
        c.keep()


def check_file_argument(path: Path, flag: str) -> Path:
    """An output file given on the command line: not a folder, its folder writable."""
    path = Path(path)
    if path.is_dir():
        raise F.FolderError(f"{flag} {str(path)!r} is a folder, not a file")
    F.check_output_path(path.parent if str(path.parent) else Path("."), flag)
    return path


def safe_name(name: str) -> str:
    """A problem's name as one folder name under results/ (the default --out): letters,
    digits, '-', '_' and '.' kept, anything else (a '/', '..') made '_', so a name such
    as "../../etc" cannot place results outside results/."""
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name).strip(".")
    return safe or "problem"

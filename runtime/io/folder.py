"""Results folders that are never lost: path checks, a lock, an overwrite policy, cleanup.

Every command that writes a results folder goes through :func:`claim`:

1. :func:`check_output_path` before any computation: the path is not a regular file, its
   components are not too long for the file system, and the nearest existing parent is a
   writable directory (nothing is created yet).
2. :func:`existing_result` reads the folder's marker file (``summary.json``,
   ``modes.json``, ...): a folder that holds a finished result is refused unless the
   caller asked to overwrite it (or to resume it, which the caller handles).
3. :func:`claim` (a context manager) creates the folder, takes the lock file
   ``.kvrod.lock`` (created exclusively; it holds the owner's pid; a lock whose owner is no
   longer alive is taken over), removes the previous run's files when overwriting, and on
   leaving releases the lock and removes the folder again if it created it and nothing was
   written into it.

All errors are :class:`FolderError` (a ValueError) with one line naming the folder.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

LOCK_NAME = ".kvrod.lock"
#: statuses of a result that another run must not overwrite silently
FINISHED_STATUSES = ("finished", "failed", "interrupted")


class FolderError(ValueError):
    """A results folder that cannot be used (message names the folder)."""


def _name_max(directory: Path) -> int:
    try:
        return os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError):  # pragma: no cover - platforms without pathconf
        return 255


def _path_max(directory: Path) -> int:
    try:
        return os.pathconf(directory, "PC_PATH_MAX")
    except (OSError, ValueError):  # pragma: no cover
        return 4096


def check_output_path(path: Path, flag: str = "--out", longest_child: int = 40) -> Path:
    """Check that ``path`` can become (or is) a results folder; nothing is created.

    Raises :class:`FolderError` when ``path`` is an existing file, a component is longer
    than the file system allows, the whole path (plus ``longest_child`` characters for
    the files written inside) is too long, or the nearest existing ancestor is not a
    writable directory.
    """
    path = Path(path)
    if str(path) == "":
        raise FolderError(f"{flag} is empty: give a folder")
    if path.exists() and not path.is_dir():
        raise FolderError(f"{flag} {str(path)!r} is an existing file, not a folder")
    parent = path if path.exists() else path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise FolderError(f"{flag} {str(path)!r}: {str(parent)!r} is not a folder")
    name_max = _name_max(parent)
    for part in path.parts:
        if len(os.fsencode(part)) > name_max:
            raise FolderError(f"{flag} {str(path)[:60]!r}...: a path component is longer than "
                              f"{name_max} bytes, the file system's limit")
    if len(os.fsencode(str(path.absolute()))) + longest_child > _path_max(parent):
        raise FolderError(f"{flag} {str(path)[:60]!r}...: the path is too long for the file "
                          f"system ({_path_max(parent)} bytes with the files inside)")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise FolderError(f"{flag} {str(path)!r}: {str(parent)!r} is not writable")
    if path.exists() and not os.access(path, os.W_OK | os.X_OK):
        raise FolderError(f"{flag} {str(path)!r} is not writable")
    return path


def read_status(marker: Path) -> str | None:
    """The ``status`` of a JSON marker file; "finished" for a marker without one; None when
    absent. An unreadable marker counts as a result ("unreadable")."""
    if not marker.exists():
        return None
    try:
        data = json.loads(marker.read_text())
    except (OSError, ValueError):
        return "unreadable"
    if not isinstance(data, dict):
        return "unreadable"
    return str(data.get("status", "finished"))


def existing_result(path: Path, markers: Iterable[str] = ("summary.json",)) -> str | None:
    """Status of the result held in folder ``path`` (see :func:`read_status`), or None."""
    for name in markers:
        status = read_status(Path(path) / name)
        if status is not None:
            return status
    return None


#: the marker file of each command's result in a folder, and the command that writes it
RESULT_MARKERS = {"summary.json": "kvrod simulate or kvrod static",
                  "modes.json": "kvrod modes", "section.json": "kvrod section",
                  "calibration.json": "kvrod calibrate", "dma.json": "kvrod calibrate --dma",
                  "compare_damping.json": "kvrod compare-damping",
                  "study.toml": "kvrod sweep", "fit.json": "kvrod fit"}


def refuse_other_result(path: Path, command: str, markers: Iterable[str],
                        overwrite: bool = False) -> None:
    """Raise :class:`FolderError` when ``path`` holds another command's result (a marker
    of :data:`RESULT_MARKERS` not among ``markers``) and ``overwrite`` is off: a section
    result and a run are not mixed in one folder by accident. With ``overwrite`` the
    command writes beside it (and replaces only its own files)."""
    if overwrite:
        return
    own = set(markers)
    for name, writer in RESULT_MARKERS.items():
        if name not in own and (Path(path) / name).is_file():
            raise FolderError(f"kvrod {command}: results folder {str(path)!r} holds a "
                              f"`{writer}` result ({name}); choose another --out, or use "
                              "--overwrite to write beside it (its files are kept)")


def refuse_existing(path: Path, command: str, markers: Iterable[str] = ("summary.json",),
                    overwrite: bool = False, resumable: bool = False) -> str | None:
    """Raise :class:`FolderError` when ``path`` holds a result and ``overwrite`` is off:
    one of the command's own (``markers``) or another command's
    (:func:`refuse_other_result`).

    A result still marked ``running`` without a live lock is an interrupted run (SIGKILL):
    it is refused too, and the message points at ``--resume`` where the command has it.
    Returns the existing status (None for an empty or new folder).
    """
    holder = lock_holder(path)
    if holder is not None:
        raise FolderError(f"kvrod {command}: results folder {str(path)!r} is in use by process "
                          f"{holder} (lock file {LOCK_NAME}); wait for it or choose another "
                          "--out")
    markers = tuple(markers)
    status = existing_result(path, markers)
    if status is None:
        refuse_other_result(path, command, markers, overwrite)
    if status is None or overwrite:
        return status
    hint = "use --overwrite to replace it" + (" or --resume to continue it" if resumable
                                               else "")
    raise FolderError(f"kvrod {command}: results folder {str(path)!r} already holds a "
                      f"{status} result; {hint} (or choose another --out)")


def lock_holder(path: Path) -> int | None:
    """The pid of the live process holding ``path``'s lock, or None."""
    lock = Path(path) / LOCK_NAME
    try:
        holder = json.loads(lock.read_text()).get("pid", -1)
    except (OSError, ValueError, AttributeError):
        return None
    if isinstance(holder, int) and holder != os.getpid() and _pid_alive(holder):
        return holder
    return None


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


@dataclass
class Claim:
    """An acquired results folder (see :func:`claim`)."""

    path: Path
    created: bool
    lock: Path

    def keep(self) -> None:
        """Mark the folder as holding results (it is not removed on release)."""
        self.created = False


def _take_lock(lock: Path, command: str) -> None:
    payload = json.dumps({"pid": os.getpid(), "command": command}).encode()
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                holder = json.loads(lock.read_text()).get("pid", -1)
            except (OSError, ValueError, AttributeError):
                holder = -1
            if isinstance(holder, int) and _pid_alive(holder) and holder != os.getpid():
                raise FolderError(f"results folder {str(lock.parent)!r} is in use by process "
                                  f"{holder} (lock file {lock.name}); wait for it or choose "
                                  "another --out") from None
            with contextlib.suppress(FileNotFoundError):  # stale: its owner is gone
                lock.unlink()
            if isinstance(holder, int) and holder > 0:      # and its half-written files
                for stale in lock.parent.rglob(f".*.{holder}.tmp*"):
                    with contextlib.suppress(OSError):
                        stale.unlink()
            continue
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
        return
    raise FolderError(f"results folder {str(lock.parent)!r}: cannot take the lock {lock.name}")


def remove_previous(path: Path, names: Iterable[str] = (), patterns: Iterable[str] = ()) -> None:
    """Remove a previous run's files from ``path``: the given names (files or folders) and
    glob patterns. Nothing else is touched (a folder may hold the user's own files)."""
    path = Path(path)
    victims = [path / n for n in names] + [p for pat in patterns for p in path.glob(pat)]
    for v in victims:
        if v.name == LOCK_NAME:
            continue
        if v.is_dir() and not v.is_symlink():
            shutil.rmtree(v)
        elif v.exists() or v.is_symlink():
            v.unlink()


#: what each command writes into its folder (removed by --overwrite)
#: the figures of a run or a static result (``--plots``, ``kvrod plot``); named, not
#: globbed: a folder may hold another command's figures (section.png, mode_shapes.png,
#: which cannot all be redrawn) and the user's own pictures
RUN_FIGURES = ("ends.png", "energy.png", "damping_ratio.png", "centreline.png",
               "centreline.gif", "centreline.mp4", "shape.png")
RUN_FILES = ("summary.json", "series.npz", "checkpoint.npz", "vtk", "problem.toml",
             "static.npz", "sensitivities.npz", *RUN_FIGURES)
#: half-written files of an earlier process
RUN_PATTERNS = (".*.tmp", ".*.tmp.npz", ".*.tmp.*")


@contextlib.contextmanager
def claim(path: Path, command: str, *, overwrite: bool = False,
          names: Iterable[str] = RUN_FILES, patterns: Iterable[str] = RUN_PATTERNS
          ) -> Iterator[Claim]:
    """Create and lock results folder ``path`` for one run (see the module docstring).

    With ``overwrite`` the previous run's files (``names``, ``patterns``) are removed once
    the lock is held. On leaving, the lock is released; a folder this call created is
    removed again if it is still empty (the run failed before writing anything).
    """
    path = Path(path)
    created = not path.exists()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FolderError(f"cannot create results folder {str(path)!r}: "
                          f"{exc.strerror or exc}") from exc
    lock = path / LOCK_NAME
    try:
        _take_lock(lock, command)
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                path.rmdir()
        raise
    c = Claim(path=path, created=created, lock=lock)
    try:
        if overwrite:
            remove_previous(path, names, patterns)
        yield c
    finally:
        with contextlib.suppress(OSError):
            lock.unlink()
        if c.created:
            with contextlib.suppress(OSError):
                path.rmdir()  # only succeeds when nothing was written


def is_disk_full(exc: BaseException) -> bool:
    """True for the OSErrors of a full disk or quota."""
    return isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


@contextlib.contextmanager
def results_folder(out: Path, command: str, *, markers: Iterable[str], overwrite: bool,
                   names: Iterable[str], patterns: Iterable[str] = RUN_PATTERNS
                   ) -> Iterator[Path]:
    """Check, refuse-or-overwrite and lock ``out`` for ``kvrod COMMAND`` before anything is
    computed; yields the path.

    ``markers``: the files whose presence means "this folder holds a result";
    ``names``/``patterns``: what the command writes (removed by ``overwrite``).
    """
    out = Path(out)
    check_output_path(out)
    refuse_existing(out, command, tuple(markers), overwrite=overwrite)
    with claim(out, command, overwrite=overwrite, names=names, patterns=patterns) as c:
        yield out
        c.keep()


def check_file_argument(path: Path, flag: str) -> Path:
    """An output file given on the command line: not a folder, its folder writable."""
    path = Path(path)
    if path.is_dir():
        raise FolderError(f"{flag} {str(path)!r} is a folder, not a file")
    check_output_path(path.parent if str(path.parent) else Path("."), flag)
    return path


def safe_name(name: str) -> str:
    """A problem's name as one folder name under results/ (the default --out): letters,
    digits, '-', '_' and '.' kept, anything else (a '/', '..') made '_', so a name such
    as "../../etc" cannot place results outside results/."""
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name).strip(".")
    return safe or "problem"

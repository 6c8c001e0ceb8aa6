"""What the command line says on stderr during long phases: the first derivation (step by
step) and the first C compilation. The library only calls back (derive.pipeline.Progress,
runtime.native.add_compile_observer); the words are printed here."""

from __future__ import annotations

import sys
from typing import Any


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class DerivationProgress:
    """``progress(done, total, entry)`` for :func:`derive.pipeline.run`: a line saying that
    the model is being derived (and where it will be cached), then a tqdm bar over the steps
    on a terminal, else one line per step."""

    def __init__(self, command: str = "kvrod") -> None:
        self.command = command
        self.bar: Any = None

    def __call__(self, done: int, total: int, entry) -> None:
        if done == 0:
            from derive import cache

            where = (f"cached afterwards in {cache.cache_dir()}" if cache.enabled()
                     else "not cached: KVROD_DERIVE_CACHE=0")
            _say(f"{self.command}: deriving the model from 3-D theory ({total} SymPy steps, "
                 f"about half a minute; {where})")
            if sys.stderr.isatty():
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit="step", leave=False, file=sys.stderr,
                                bar_format="{desc}: {n}/{total} steps [{elapsed}]")
        if self.bar is not None:
            self.bar.n = done
            self.bar.set_description(entry.name if entry is not None else "done")
            if entry is None:
                self.bar.close()
                self.bar = None
        elif entry is not None:
            _say(f"  step {done + 1}/{total}: {entry.name}")


def derivation(command: str = "kvrod") -> dict:
    """The derivation's step records, with progress on stderr when they must be derived
    (kept for the rest of the process, so later calls need no progress)."""
    from derive.pipeline import run

    return run(progress=DerivationProgress(command))


def _compile_notice(what: str, seconds: float | None) -> None:
    from runtime.native import TYPICAL_SECONDS

    if seconds is None:
        typical = TYPICAL_SECONDS.get(what)
        about = f", ~{typical} s" if typical else ""
        _say(f"kvrod: compiling {what} (first use{about}; cached afterwards)...")
    else:
        _say(f"kvrod: compiled {what} in {seconds:.1f} s")


def install_compile_notices() -> None:
    """Print a line on stderr when a C compilation starts and ends."""
    from runtime import native

    native.add_compile_observer(_compile_notice)


def remove_compile_notices() -> None:
    """Undo :func:`install_compile_notices` (the CLI's main does, so that calling it
    in-process, e.g. from tests, leaves no observer behind)."""
    mod = sys.modules.get("runtime.native")
    if mod is not None:
        mod.remove_compile_observer(_compile_notice)

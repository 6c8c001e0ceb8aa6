"""The `kvrod` command line.

Every command imports its layer lazily, so `kvrod simulate` never loads SymPy and a bad
flag is rejected before any heavy import. Errors are one line on stderr with a non-zero
exit code; library code never prints, this module does.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from kvrod.errors import CliError


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line instead of usage + message
        raise CliError(f"{self.prog}: {message} (see `{self.prog} --help`)")


def _cmd_derive_list(args) -> int:
    """The catalogue of steps, with each step's verdict against its stated forms when a
    derivation is cached. Derives nothing and imports no SymPy."""
    from derive import cache
    from derive.pipeline import PIPELINE

    verdicts = cache.summary()
    known = verdicts["steps"] if verdicts else {}
    if args.json:
        print(json.dumps([{"name": e.name, "title": e.title, "equations": list(e.equations),
                           "inputs": list(e.inputs),
                           "all_match": known.get(e.name, {}).get("all_match")}
                          for e in PIPELINE]))
        return 0
    width = max(len(e.name) for e in PIPELINE)
    for e in PIPELINE:
        v = known.get(e.name)
        ok = "-   " if v is None else ("ok  " if v["all_match"] else "DIFF")
        print(f"{e.name:<{width}}  {ok}  {' '.join(e.equations):<28} {e.title}")
    if not known:
        print("kvrod derive list: not derived yet, so the column 'ok' (every stated form "
              "matches) is '-': `kvrod derive show STEP` derives all steps once (about half "
              "a minute; cached afterwards)", file=sys.stderr)
    return 0


def _show_text(s) -> str:
    import sympy as sp

    out = [f"{s.name}: {s.title}", f"paper: {', '.join(s.equations)}",
           f"inputs: {', '.join(s.inputs) or '(3-D theory)'}", "assumptions:"]
    out += [f"  - {a}" for a in s.assumptions + s.symbol_assumptions]
    out.append("results:")
    for k, v in s.results.items():
        mark = ""
        if k in s.matches:
            mark = "   [= stated]" if s.matches[k] else "   [DIFFERS from stated]"
        out.append(f"  {k}{mark}:")
        pretty = sp.pretty(v, use_unicode=True, wrap_line=False)
        out += ["    " + line for line in pretty.splitlines()]
    if s.notes:
        out.append("notes:")
        out += [f"  - {n}" for n in s.notes]
    return "\n".join(out)


def _show_latex(s) -> str:
    import sympy as sp

    from derive.step import latex_name

    out = [f"% {s.name}: {s.title} -- paper {', '.join(s.equations)}", r"\begin{align}"]
    rows = [rf"{latex_name(k)} &= {sp.latex(v)}" for k, v in s.results.items()]
    out.append(" \\\\\n".join(rows))
    out.append(r"\end{align}")
    return "\n".join(out)


def _cmd_derive_show(args) -> int:
    from derive.pipeline import STEP_NAMES
    from kvrod.notices import derivation

    if args.step not in STEP_NAMES:
        raise CliError(f"kvrod derive show: unknown step {args.step!r}; "
                       f"steps are: {', '.join(STEP_NAMES)}")
    s = derivation("kvrod derive show")[args.step]
    print(_show_latex(s) if args.latex else _show_text(s))
    return 0


def _cmd_derive_export(args) -> int:
    import sympy as sp

    from derive.pipeline import STEP_NAMES
    from kvrod.notices import derivation

    names = args.steps or list(STEP_NAMES)
    bad = [n for n in names if n not in STEP_NAMES]
    if bad:
        raise CliError(f"kvrod derive export: unknown step(s) {', '.join(map(repr, bad))}; "
                       f"steps are: {', '.join(STEP_NAMES)}")
    _check_output(args.out, "kvrod derive export")
    steps = derivation("kvrod derive export")
    doc = {n: {"title": steps[n].title, "equations": list(steps[n].equations),
               "assumptions": list(steps[n].assumptions), "inputs": list(steps[n].inputs),
               "results": {k: {"latex": sp.latex(v), "text": sp.sstr(v), "srepr": sp.srepr(v)}
                           for k, v in steps[n].results.items()},
               "matches_paper": dict(steps[n].matches)} for n in names}
    text = json.dumps(doc, indent=1)
    if args.out:
        Path(args.out).write_text(text + "\n")
        print(f"wrote {args.out}")
    else:
        print(text)
    return 0


def _check_output(path: str | Path | None, command: str, folder: bool = False) -> None:
    """Refuse an output path that cannot be written before the derivation runs (half a
    minute on an empty cache): a file where a folder must be, or a folder where the file
    must be."""
    if path is None:
        return
    p = Path(path)
    if p.is_dir() and not folder:
        raise CliError(f"{command}: --out {path} is a folder; give a file name")
    for anc in ([p] if folder else []) + list(p.parents):
        if anc.exists():
            if not anc.is_dir():
                raise CliError(f"{command}: --out {path}: {anc} is a file, not a folder")
            return


def _cmd_derive_notes(args) -> int:
    from derive.notes import write_derivation_notes
    from kvrod.notices import derivation

    _check_output(args.out, "kvrod derive notes")
    derivation("kvrod derive notes")
    path = write_derivation_notes(Path(args.out))
    print(f"wrote {path}")
    return 0


def _cmd_generate(args) -> int:
    from derive.artifacts import check_tree, write_tree
    from kvrod.notices import derivation

    _check_output(args.out, "kvrod generate", folder=True)
    derivation("kvrod generate")
    if args.check:
        problems = check_tree(Path(args.out) if args.out else None)
        if problems:
            print("generated/ is stale; run `kvrod generate`:", file=sys.stderr)
            for p in problems:
                print("  " + p.replace("\n", "\n    "), file=sys.stderr)
            return 1
        print("generated/ is up to date")
        return 0
    paths = write_tree(Path(args.out) if args.out else None)
    print(f"wrote {len(paths)} files to {paths[0].parent}")
    return 0


def _cmd_bench(args) -> int:
    try:
        import bench
    except ImportError as exc:
        raise CliError(f"kvrod bench: the bench/ package is not available ({exc})") from exc
    if not hasattr(bench, "run_all"):
        raise CliError("kvrod bench: bench.run_all is not available in this checkout")
    try:
        bench.run_all(quick=args.quick, out_dir=Path(args.out),
                      only=tuple(args.only) if args.only else None)
    except ValueError as exc:  # an unknown section name (the message lists the allowed ones)
        raise CliError(f"kvrod bench: {exc}") from exc
    return 0


def _cmd_problem_keys(args) -> int:
    from runtime.problem import keys

    print(keys.markdown() if args.markdown else keys.text())
    return 0


class _VersionAction(argparse.Action):
    def __call__(self, parser, namespace, values, option_string=None):
        from runtime.version import version_text

        print(version_text())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="kvrod", description=__doc__.splitlines()[0] if __doc__ else None)
    p.add_argument("--version", action=_VersionAction, nargs=0,
                   help="the kvrod version and the hash of the generated code, then exit")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    d = sub.add_parser("derive", help="inspect the SymPy derivation")
    dsub = d.add_subparsers(dest="derive_command", required=True, parser_class=_Parser)
    dl = dsub.add_parser("list", help="list the derivation steps")
    dl.add_argument("--json", action="store_true", help="names and inputs as JSON (no SymPy)")
    dl.set_defaults(func=_cmd_derive_list)
    ds = dsub.add_parser("show", help="show one step")
    ds.add_argument("step")
    ds.add_argument("--latex", action="store_true", help="LaTeX instead of pretty text")
    ds.set_defaults(func=_cmd_derive_show)
    de = dsub.add_parser("export", help="export steps as JSON (LaTeX, text, srepr)")
    de.add_argument("steps", nargs="*", help="step names (default: all)")
    de.add_argument("--out", help="output file (default: stdout)")
    de.set_defaults(func=_cmd_derive_export)
    dn = dsub.add_parser("notes", help="write notes/derivation.md")
    dn.add_argument("--out", default="notes/derivation.md")
    dn.set_defaults(func=_cmd_derive_notes)

    k = sub.add_parser("problem-keys", help="every key of a problem file: unit, default, "
                                            "allowed range, meaning")
    k.add_argument("--markdown", action="store_true", help="Markdown tables")
    k.set_defaults(func=_cmd_problem_keys)

    g = sub.add_parser("generate", help="regenerate generated/ (or --check it)")
    g.add_argument("--check", action="store_true", help="fail if generated/ is stale")
    g.add_argument("--out", help="target folder (default: the generated/ package)")
    g.set_defaults(func=_cmd_generate)

    from kvrod import cli_analysis, cli_fit, cli_notes, cli_runtime, cli_section, cli_sweep

    cli_runtime.add_commands(sub, _Parser)
    cli_sweep.add_commands(sub, _Parser)
    cli_analysis.add_commands(sub, _Parser)
    cli_fit.add_commands(sub, _Parser)
    cli_notes.add_commands(sub, _Parser)
    cli_section.add_commands(sub, _Parser)
    b = sub.add_parser("bench", help="run the benchmarks in bench/ (JSON + Markdown)")
    b.add_argument("--quick", action="store_true", help="small sizes only (< 1 min)")
    b.add_argument("--out", default="bench/results", help="results folder")
    b.add_argument("--only", action="append", metavar="SECTION",
                   help="run only this section (repeatable; the README reads the others "
                        "back from their JSON)")
    b.set_defaults(func=_cmd_bench)
    return p


def _on_sigterm(signum, frame):  # pragma: no cover - exercised through subprocesses
    from runtime.errors import Terminated

    raise Terminated()


def _command_name(argv: Sequence[str] | None) -> str:
    args = list(sys.argv[1:] if argv is None else argv)
    words = [a for a in args[:2] if not a.startswith("-")]
    return " ".join(["kvrod", *words[:1]])


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


#: optional packages (top-level module -> the pyproject extra that installs it)
OPTIONAL_PACKAGES = {"elastica": "bench", "vtk": "vtk", "sphinx": "docs", "myst_nb": "docs",
                     "jupyter_cache": "docs", "furo": "docs", "pytest": "test",
                     "hypothesis": "test", "sectionproperties": "test"}


def missing_package_line(prefix: str, module: str) -> str:
    """One line for a package that is not installed, with the command that installs it: an
    optional extra of kvrod, or a reinstall of kvrod for a core dependency."""
    top = module.split(".")[0]
    extra = OPTIONAL_PACKAGES.get(top)
    how = (f"pip install -e '.[{extra}]' (in a checkout; or pip install 'kvrod[{extra}]')"
           if extra else "pip install -e . (a core dependency of kvrod is missing: "
           "reinstall it)")
    return f"{prefix}: the Python package {top!r} is not installed; install it with: {how}"


def _error_line(prefix: str, exc: BaseException) -> tuple[str, int]:
    """(message, exit code) for an exception that reached the command line."""
    from runtime.errors import GeneratedCodeError

    if isinstance(exc, CliError):
        return str(exc), 2
    if isinstance(exc, ModuleNotFoundError) and exc.name:
        return missing_package_line(prefix, exc.name), 2
    if isinstance(exc, MemoryError):
        return (f"{prefix}: out of memory: the problem is too large for this machine "
                "(reduce n_elements, t_end or the output density)"), 2
    if isinstance(exc, GeneratedCodeError):
        return f"{prefix}: generated code: {_one_line(exc)}", 2
    if isinstance(exc, OSError):
        where = exc.filename if exc.filename is not None else ""
        what = exc.strerror or type(exc).__name__
        from runtime.io.folder import is_disk_full

        hint = " (disk full: free space and run again)" if is_disk_full(exc) else ""
        return (f"{prefix}: cannot access {str(where)!r}: {what}{hint}" if where
                else f"{prefix}: {what}: {_one_line(exc)}{hint}"), 2
    if isinstance(exc, ValueError):  # parameter, config, folder, checkpoint errors
        msg = _one_line(exc)
        return (msg if msg.startswith("kvrod") else f"{prefix}: error: {msg}"), 2
    return (f"{prefix}: internal error: {type(exc).__name__}: {_one_line(exc)} (this is a "
            "bug in kvrod; KVROD_DEBUG=1 shows the traceback)"), 3


#: commands that never compile C (and should not import the runtime to say so)
_NO_COMPILE = ("derive", "generate", "problem-keys", "section", "notes-sections")

#: commands whose BLAS calls are small (rod runs): OpenBLAS's idle threads may sleep at once
_QUIET_BLAS = ("simulate", "sweep")


def quiet_blas_threads(command: str, environ=None, numpy_loaded: bool | None = None) -> bool:
    """Let OpenBLAS's idle threads sleep at once in a rod run (``OPENBLAS_THREAD_TIMEOUT
    = 4``, 2^4 cycles, unless the user set it); True when set.

    OpenBLAS starts its threads when NumPy loads and lets each spin for 2^28 cycles
    (~0.1 s) waiting for work before it sleeps: CPU a short ``kvrod simulate`` pays
    (0.45 -> 0.32 s of a 10-element run here) and, on a busy machine, takes from the
    run's own thread. The threading itself is unchanged (the same BLAS calls split the
    same way), so every result is too. Only before NumPy is imported (OpenBLAS reads it
    then), only for ``_QUIET_BLAS`` (``kvrod section``'s dense blocks keep the
    default)."""
    import os

    environ = os.environ if environ is None else environ
    loaded = "numpy" in sys.modules if numpy_loaded is None else numpy_loaded
    if command not in _QUIET_BLAS or loaded or "OPENBLAS_THREAD_TIMEOUT" in environ:
        return False
    environ["OPENBLAS_THREAD_TIMEOUT"] = "4"
    return True


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one stderr line (its message), not Python's file:line format."""
    print(str(message), file=sys.stderr, flush=True)


def _stopped(code: int, argv: Sequence[str] | None) -> int:
    """The exit code of an interrupted command. As the program itself (``argv`` None: the
    console script, ``python -m kvrod``) with a computation still running in a worker
    thread (a section analysis inside a factorization), the process ends here with
    ``os._exit``: the interpreter's normal exit under such a thread may crash
    (:func:`runtime.signals.workers_alive`). Called in-process (tests), it returns."""
    import os

    from runtime.signals import workers_alive

    if argv is None and workers_alive():
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    return code


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `kvrod` console script: the one error boundary of the CLI.

    Every error becomes one line on stderr naming the parameter, flag or file: exit 2 for
    bad input, I/O and integrity errors, 130 for Ctrl-C, 143 for SIGTERM, 3 for a bug
    (an unexpected exception; ``KVROD_DEBUG=1`` re-raises it with its traceback).
    """
    if list(sys.argv[1:] if argv is None else argv) == ["--version"]:
        from runtime.version import version_text  # the one answer that needs no parser

        print(version_text())
        raise SystemExit(0)                          # as argparse's --version action does
    import os
    import signal

    prefix = _command_name(argv)
    try:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:  # not the main thread (e.g. called from a test runner thread)
        previous = None
    import warnings

    try:
        with warnings.catch_warnings():
            # floating-point RuntimeWarnings (overflow in NumPy or matplotlib) are no
            # message for the user: whatever they foreshadow is checked and reported as
            # one line (a non-finite solve, a rejected fit)
            warnings.simplefilter("ignore", RuntimeWarning)
            # kvrod's own warnings (a degraded path, a doubtful result: their message
            # starts with "kvrod") are one line on stderr each, whatever their category
            warnings.filterwarnings("always", message="kvrod")
            warnings.showwarning = _show_warning
            parser = build_parser()
            args = parser.parse_args(argv)
            quiet_blas_threads(args.command)
            import shlex

            # the command as typed, for the measurements the notes commands write
            args.command_line = shlex.join(["kvrod",
                                            *(sys.argv[1:] if argv is None else argv)])
            if args.command not in _NO_COMPILE:
                from kvrod.notices import install_compile_notices

                install_compile_notices()
            return int(args.func(args) or 0)
    except BrokenPipeError:  # e.g. `kvrod derive show X | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("kvrod: interrupted", file=sys.stderr)
        return _stopped(130, argv)
    except SystemExit:
        raise
    except BaseException as exc:
        from runtime.errors import Terminated

        if isinstance(exc, Terminated):
            print("kvrod: terminated", file=sys.stderr)
            return _stopped(143, argv)
        if not isinstance(exc, Exception):
            raise
        if os.environ.get("KVROD_DEBUG", "") not in ("", "0"):
            raise
        message, code = _error_line(prefix, exc)
        print(message, file=sys.stderr)
        return code
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
        from kvrod.notices import remove_compile_notices

        remove_compile_notices()
        if argv is None:
            _leave_heap_to_the_os()


def _leave_heap_to_the_os() -> None:
    """The program is about to exit: move every object to the collector's permanent
    generation (``gc.freeze``), so that the interpreter's last full collection does not
    walk the heap that NumPy, Dask and matplotlib built. Measured here: 0.1-0.2 s of a
    ``kvrod simulate`` of 0.5 s, 0.3-0.5 s of a ``kvrod sweep`` on Dask. Everything else
    of a normal exit still happens (atexit handlers, weakref finalizers, flushed
    streams, objects freed by their reference counts); objects in unreachable reference
    cycles are left to the operating system with the process's memory, their ``__del__``
    not run (no kvrod object relies on one: files are closed by ``with``, and the study
    table, the one file kept open, is flushed at every row)."""
    import gc

    gc.freeze()


if __name__ == "__main__":
    # run the imported module's main, so that its exception classes are the ones the
    # command modules raise (``python -m kvrod.cli`` would otherwise have two copies)
    from kvrod.cli import main as _main

    sys.exit(_main())

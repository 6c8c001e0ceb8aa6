"""The adversarial table (tests/app/adversarial_cases.py), run against the CLI.

Every case asserts the same contract:

* the exit code (0 / 1 / 2 / 130; SIGTERM 143 or 130);
* on failure, exactly one non-empty stderr line (progress bars aside), starting with
  ``kvrod`` and naming the culprit (the case's needles, case-insensitive);
* never "Traceback" in stdout or stderr (in-process: no exception escapes ``main``);
* the results folder afterwards (unchanged / absent / status / files), no stray ``.tmp``
  files and no ``.kvrod.lock`` left behind (unless another live process holds it).

Cheap cases run in-process (``kvrod.cli.main``); signals, locks of two processes, read-only
folders and resource limits run as subprocesses. The long subprocess cases (hostile
calibration data, huge studies) start early in two background lanes so that they overlap
with the in-process ones.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.app import adversarial_cases as A

CASES = A.CASES
#: subprocess cases running at the same time as the in-process ones
BACKGROUND_LANES = 2


def _param(case: A.Case):
    marks = [pytest.mark.slow] if case.slow else []
    return pytest.param(case, id=f"{case.kind}:{case.id}", marks=marks)


# --------------------------------------------------------------------------------------
# the table itself
# --------------------------------------------------------------------------------------


def test_table_is_well_formed():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids)), "duplicate case ids"
    assert len(CASES) >= 110, len(CASES)
    for c in CASES:
        assert c.kind in A.KINDS, c.id
        assert c.mode in ("inproc", "subproc", "custom"), c.id
        assert (c.run is not None) == (c.mode == "custom"), c.id
        assert not (c.background and c.mode != "subproc"), c.id
        if any(code != 0 for code in c.exits):
            assert c.needles, f"{c.id}: a failing case must name its culprit"


# --------------------------------------------------------------------------------------
# fixtures
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def templates(tmp_path_factory):
    return A.Templates(tmp_path_factory.mktemp("adv-templates"))


def _prepare(case: A.Case, tmp: Path, templates) -> A.Ctx:
    ctx = A.Ctx(tmp=tmp, out=tmp / A.OUT_NAME, templates=templates)
    for fn in case.setup:
        fn(ctx)
    ctx.snapshot = A.snapshot(ctx.out)
    # what a SIGKILLed earlier run left (a stale lock, a half-written temporary file): a
    # refused command must leave it alone, a successful one must clean it up
    ctx.vars["_stale"] = {A.LOCK_NAME} if A.lexists(ctx.out / A.LOCK_NAME) else set()
    ctx.vars["_stale"] |= set(A.stray_tmp(ctx.out))
    return ctx


def _run_subprocess(case: A.Case, ctx: A.Ctx) -> A.Result:
    pre = []
    if case.as_limit:
        pre.append(A.limit_as(case.as_limit))
    if case.fsize_limit:
        pre.append(A.limit_fsize(case.fsize_limit))
    argv = [ctx.fmt(a) for a in case.argv]
    return A.run_subprocess(ctx, argv, case.timeout, pre)


@pytest.fixture(scope="module")
def background(request, tmp_path_factory, templates):
    """Start the selected background cases now, in two lanes, longest time limit first."""
    selected = [item.callspec.params["case"] for item in request.session.items
                if getattr(item, "module", None) is sys.modules[__name__]
                and getattr(item, "originalname", "") == "test_case"
                and item.callspec.params["case"].background]
    selected.sort(key=lambda c: -c.timeout)
    if selected:
        # the compiled library in the cache first: on an empty cache (a fresh CI machine)
        # the first subprocess compiles and says so on stderr, beside the one line a case
        # checks (and two lanes would compile at once)
        from runtime.model.build import compile_native

        compile_native()
    pool = ThreadPoolExecutor(max_workers=BACKGROUND_LANES)
    lane: dict[str, tuple[A.Ctx, Future]] = {}
    for case in selected:
        ctx = _prepare(case, tmp_path_factory.mktemp("adv-bg"), templates)
        lane[case.id] = (ctx, pool.submit(_run_subprocess, case, ctx))
    yield lane
    for ctx, fut in lane.values():
        fut.cancel()
        for p in ctx.procs:
            A.kill_group(p)
    pool.shutdown(wait=True, cancel_futures=True)


# --------------------------------------------------------------------------------------
# the guard: inputs that must be refused before any computation starts
# --------------------------------------------------------------------------------------


class ComputationStarted(BaseException):  # noqa: N818 - not an error of the product
    """Raised by the guarded entry points (a BaseException, so no `except Exception`
    in the product swallows it)."""


_GUARDED = (("runtime.simulate.simulate", "simulate"),
            ("runtime.analysis.modal", "modal_analysis"),
            ("runtime.solvers.statics", "solve_static"), ("runtime.study.sweep", "run_point"),
            ("runtime.study.compare_damping", "compare_damping"),
            ("runtime.study.calibration", "calibrate_signal"),
            ("runtime.study.calibration", "calibrate_decrements"),
            ("runtime.section.analysis", "analyse_section"))
_PREIMPORT = ("runtime.simulate.simulate", "runtime.analysis.modal", "runtime.solvers.statics",
              "runtime.study.sweep", "runtime.study.calibration",
              "runtime.study.compare_damping", "reports.reproduction", "reports.damping_studies",
              "kvrod.cli_analysis", "kvrod.cli_notes", "kvrod.cli_runtime", "kvrod.cli_sweep",
              "runtime.section", "runtime.problem.section_analysis", "kvrod.cli_section")


def _install_guard(monkeypatch) -> None:
    import importlib

    for name in _PREIMPORT:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)
    originals = {}
    for mod, attr in _GUARDED:
        with contextlib.suppress(ImportError, AttributeError):
            originals[id(getattr(importlib.import_module(mod), attr))] = attr

    def guard(name):
        def f(*a, **k):
            raise ComputationStarted(f"{name} started before the input was rejected")
        return f

    for modname, mod in list(sys.modules.items()):
        if not modname.startswith(("runtime", "kvrod")) or mod is None:
            continue
        for attr, value in list(vars(mod).items()):
            if id(value) in originals and callable(value):
                monkeypatch.setattr(mod, attr, guard(originals[id(value)]))


# --------------------------------------------------------------------------------------
# the contract
# --------------------------------------------------------------------------------------


def _needle_ok(needle, line: str, ctx: A.Ctx) -> bool:
    alts = needle if isinstance(needle, tuple) else (needle,)
    return any(ctx.fmt(a).lower() in line.lower() for a in alts)


def _verify(case: A.Case, ctx: A.Ctx, r: A.Result) -> list[str]:
    problems = []
    if r.escaped:
        problems.append(f"exception escaped main(): {r.escaped[:300]}")
    if r.timed_out:
        problems.append(f"still running after {case.timeout:.0f} s (killed)")
    traceback = "Traceback" in r.stdout + r.stderr
    if traceback:
        problems.append("'Traceback' in the output")
    if r.rc not in case.exits:
        problems.append(f"exit code {r.rc}, expected {' or '.join(map(str, case.exits))}")
    if r.rc is not None and r.rc != 0 and not traceback:
        lines = A.stderr_lines(r.stderr)
        if len(lines) != 1 or not lines[0].startswith("kvrod"):
            problems.append(f"stderr must be one line starting with 'kvrod', got "
                            f"{len(lines)}: {[ln[:160] for ln in lines[:4]]}")
        if lines:
            missing = [n for n in case.needles_for(r.rc)
                       if not any(_needle_ok(n, ln, ctx) for ln in lines[:1])]
            if missing:
                problems.append(f"stderr line does not name {missing}: {lines[0][:300]!r}")
    for fn in case.check:
        msg = fn(ctx, r)
        if msg:
            problems.append(msg)
    lock = ctx.out / A.LOCK_NAME
    if ctx.planted_lock is not None:
        if not A.lexists(lock) or lock.read_bytes() != ctx.planted_lock:
            problems.append(f"the live holder's {A.LOCK_NAME} was removed or replaced")
    stale = ctx.vars.get("_stale", set()) if r.rc not in (0, None) else set()
    if ctx.planted_lock is None and A.lexists(lock) and A.LOCK_NAME not in stale:
        problems.append(f"{A.LOCK_NAME} left in the results folder")
    tmp = [f for f in A.stray_tmp(ctx.out) if f not in stale]
    if tmp:
        problems.append(f"stray temporary files: {tmp[:5]}")
    return problems


def _today(r: A.Result) -> str:
    """One line on what happened (for the report)."""
    lines = [ln for ln in A.stderr_lines(r.stderr) if ln]
    if r.escaped:
        first = r.escaped
    elif "Traceback" in r.stderr:
        first = next((ln for ln in reversed(lines) if ln and not ln.startswith("File ")), "")
    else:
        first = lines[0] if lines else (r.stdout.strip().splitlines() or [""])[-1]
    info = f" ({r.info})" if r.info else ""
    return f"exit {r.rc} in {r.elapsed:.1f} s{info}: {first[:200]}"


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_case(case: A.Case, tmp_path, monkeypatch, templates, background):
    if case.background and case.id in background:
        ctx, fut = background[case.id]
        try:
            r = fut.result(timeout=case.timeout + 600)
        finally:
            for p in ctx.procs:
                A.kill_group(p)
    else:
        monkeypatch.chdir(tmp_path)
        ctx = _prepare(case, tmp_path, templates)
        try:
            if any(fn is A.readonly_parent for fn in case.setup):
                _require_readonly(ctx)
            if case.mode == "custom":
                r = case.run(ctx)
            elif case.mode == "subproc":
                r = _run_subprocess(case, ctx)
            else:
                if case.guard:
                    _install_guard(monkeypatch)
                r = A.run_inprocess([ctx.fmt(a) for a in case.argv])
        finally:
            for p in ctx.procs:
                A.kill_group(p)
                with contextlib.suppress(Exception):
                    p.wait(timeout=10)
            ro = tmp_path / "readonly_dir"
            if ro.exists():
                ro.chmod(0o755)
    problems = _verify(case, ctx, r)
    if problems:
        pytest.fail(f"[{case.kind}] {case.id}: {_today(r)}\n  - " + "\n  - ".join(problems),
                    pytrace=False)


def _require_readonly(ctx: A.Ctx) -> None:
    """Skip when this machine cannot make a folder read-only for the child process."""
    probe = ctx.out.parent / "probe"
    import subprocess

    try:
        r = subprocess.run(["touch", str(probe)], preexec_fn=A._child_setup(ctx.preexec),
                           capture_output=True, timeout=30)
    except (OSError, subprocess.SubprocessError) as exc:
        pytest.skip(f"cannot drop write permission for a child process: {exc}")
    if r.returncode == 0 or shutil.which("touch") is None:
        with contextlib.suppress(OSError):
            os.chmod(ctx.out.parent, 0o755)
            probe.unlink()
        pytest.skip("a read-only folder is writable here (root with CAP_DAC_OVERRIDE?)")

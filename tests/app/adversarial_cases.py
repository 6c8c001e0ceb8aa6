"""The adversarial table: what a hostile or careless user does to `kvrod`, and what must happen.

Every row of :data:`CASES` is one :class:`Case`: an id, a kind (``data_loss``,
``wrong_answer``, ``traceback``, ``message``, ``hang``), the argv (with placeholders), the
expected exit code(s), the words the single stderr line must contain, the setup of the
results folder and the checks of its state afterwards. ``tests/app/test_adversarial.py``
runs them all (in-process where that is faithful, as subprocesses where a real process is
needed: signals, locks of two processes, read-only folders, resource limits).

The behaviour asserted here (exit codes 0 / 1 / 2 / 130, one stderr line starting with
``kvrod`` that names the culprit, no traceback, validation before writing, ``--overwrite``,
the ``DIR/.kvrod.lock`` lock, ``kvrod: warning:`` lines, ...) is the specification the core
engineers fix the code to; many rows fail against the code of the day on purpose.

Placeholders in argv and needles: ``{out}`` (the results folder of the case), ``{out_name}``
(its base name), ``{tmp}`` (the case's scratch folder), ``{data}`` (the synthetic decay
record in tests/app/data), ``{pid}`` (the pid of a lock holder, set by the setup).
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# --------------------------------------------------------------------------------------
# assumptions about the specified interface (one place to change them)
# --------------------------------------------------------------------------------------

#: flag that allows replacing a finished result in a results folder
OVERWRITE_FLAG = "--overwrite"
#: flag that confirms a study above GRID_LIMIT points
CONFIRM_FLAG = "--yes"
#: largest study accepted without CONFIRM_FLAG (the table only relies on "far above it")
GRID_LIMIT = 10_000
#: lock file a command holds while it writes a results folder
LOCK_NAME = ".kvrod.lock"
#: a command must give up (or finish) within this many seconds on hostile data
HANG_TIMEOUT = 60.0
#: relative energy-audit error above which a finished run must carry a warning
ENERGY_WARN = 1e-3

KINDS = ("data_loss", "wrong_answer", "traceback", "message", "hang")

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data" / "decay_tau50ms.csv"
OUT_NAME = "res_adv"

#: words of a parameter error that states the allowed range (any of them)
#: (argv strings are formatted with the placeholders below: an inline TOML table's braces
#: are doubled, {{...}})
RANGE = ("range", "allowed", "at most", "at least", "between", "<", ">", "must be")


# --------------------------------------------------------------------------------------
# the case record
# --------------------------------------------------------------------------------------


@dataclass
class Result:
    """What one run of the CLI did."""

    rc: int | None                 # None: it did not end (timeout) or raised (in-process)
    stdout: str = ""
    stderr: str = ""
    elapsed: float = 0.0
    escaped: str = ""              # in-process: the exception that escaped main()
    timed_out: bool = False
    info: str = ""                 # what the report should say besides the output


@dataclass
class Ctx:
    """The scratch folder of one case, its results folder and the values of placeholders."""

    tmp: Path
    out: Path
    templates: object = None
    vars: dict = field(default_factory=dict)
    env: dict = field(default_factory=dict)
    pythonpath: list = field(default_factory=list)
    snapshot: object = None
    planted_lock: bytes | None = None
    procs: list = field(default_factory=list)      # helper processes started by the setup
    preexec: list = field(default_factory=list)    # callables run in the child (subprocess)

    def fmt(self, s: str) -> str:
        v = _Vars(out=str(self.out), out_name=self.out.name, tmp=str(self.tmp), data=str(DATA),
                  **self.vars)
        return s.format_map(v)


class _Vars(dict):
    def __missing__(self, key: str) -> str:       # an unset placeholder stays visible
        return "{" + key + "}"


Check = Callable[[Ctx, Result], "str | None"]
Needles = tuple  # of str (must occur) or tuple[str, ...] (one of them must occur)


@dataclass(frozen=True)
class Case:
    """One adversarial input and the specified outcome."""

    id: str
    kind: str
    argv: tuple = ()
    exit: int | tuple = 2
    needles: Needles | dict = ()           # words of the one stderr line (case-insensitive)
    setup: tuple = ()                      # callables (ctx) -> None, in order
    check: tuple = ()                      # callables (ctx, result) -> failure text or None
    mode: str = "inproc"                   # inproc | subproc | custom
    run: Callable | None = None            # custom: (ctx) -> Result
    timeout: float = 120.0
    slow: bool = False
    background: bool = False               # subprocess case started early, in parallel
    guard: bool = False                    # in-process: no computation may start
    as_limit: int | None = None            # subprocess: RLIMIT_AS in bytes
    fsize_limit: int | None = None         # subprocess: RLIMIT_FSIZE in bytes
    note: str = ""

    def needles_for(self, rc: int | None) -> Needles:
        if isinstance(self.needles, dict):
            return tuple(self.needles.get(rc, ()))
        return tuple(self.needles)

    @property
    def exits(self) -> tuple:
        return self.exit if isinstance(self.exit, tuple) else (self.exit,)


# --------------------------------------------------------------------------------------
# file-system helpers
# --------------------------------------------------------------------------------------


def lexists(p: Path) -> bool:
    try:
        os.lstat(p)
    except OSError:
        return False
    return True


def snapshot(p: Path):
    """Bytes of every file under ``p`` (or of ``p`` itself), None if absent. The lock file is
    left out (a stale one may be taken over; a live holder's lock is checked separately)."""
    if not lexists(p):
        return None
    if p.is_file():
        return {"": p.read_bytes()}
    snap = {}
    for f in sorted(p.rglob("*")):
        rel = str(f.relative_to(p))
        if rel != LOCK_NAME:
            snap[rel] = f.read_bytes() if f.is_file() else "<dir>"
    return snap


def stray_tmp(p: Path) -> list[str]:
    if not lexists(p) or not p.is_dir():
        return []
    return [str(f.relative_to(p)) for f in p.rglob("*") if re.search(r"\.tmp", f.name)]


def read_json(p: Path) -> dict | None:
    try:
        return json.loads(p.read_text())
    except (OSError, ValueError):
        return None


def summary_of(ctx: Ctx) -> dict | None:
    return read_json(ctx.out / "summary.json")


def stderr_lines(text: str) -> list[str]:
    """Non-empty stderr lines without progress bars (tqdm redraws with carriage returns)."""
    parts = re.split(r"[\r\n]+", text)
    return [p.strip() for p in parts if p.strip() and "%|" not in p]


def pvd_times(path: Path) -> list[float]:
    return [float(m) for m in re.findall(r'timestep="([^"]+)"', path.read_text())]


def read_rows(path: Path) -> list[dict]:
    import csv

    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------------------
# running the CLI
# --------------------------------------------------------------------------------------


def subprocess_env(ctx: Ctx | None = None) -> dict:
    env = dict(os.environ)
    paths = [*(ctx.pythonpath if ctx else []), str(ROOT)]
    env["PYTHONPATH"] = os.pathsep.join(paths)
    env["MPLBACKEND"] = "Agg"
    env.pop("PYTEST_CURRENT_TEST", None)
    if ctx:
        env.update(ctx.env)
    return env


def _child_setup(fns: Sequence[Callable]) -> Callable:
    def pre() -> None:
        signal.signal(signal.SIGINT, signal.SIG_DFL)   # a background job may inherit SIG_IGN
        for fn in fns:
            fn()

    return pre


def limit_as(nbytes: int) -> Callable:
    def fn() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (nbytes, nbytes))

    return fn


def limit_fsize(nbytes: int) -> Callable:
    def fn() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))

    return fn


def drop_dac() -> None:
    """As root, drop CAP_DAC_OVERRIDE / CAP_DAC_READ_SEARCH so mode 0555 folders are read-only."""
    if os.geteuid() != 0:
        return
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (1, 2):
        if libc.prctl(24, cap, 0, 0, 0) != 0:            # PR_CAPBSET_DROP
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP)")


def kvrod_cmd(argv: Sequence[str]) -> list[str]:
    return [sys.executable, "-m", "kvrod", *argv]


def popen(ctx: Ctx, argv: Sequence[str], extra_pre: Sequence[Callable] = ()) -> subprocess.Popen:
    """Start `python -m kvrod argv` in its own session (so Ctrl-C can go to its group)."""
    p = subprocess.Popen(kvrod_cmd(argv), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, cwd=ctx.tmp, env=subprocess_env(ctx),
                         start_new_session=True,
                         preexec_fn=_child_setup([*ctx.preexec, *extra_pre]))
    ctx.procs.append(p)
    return p


def kill_group(p: subprocess.Popen) -> None:
    """SIGKILL a process this test started, with its process group if it leads one (the
    Dask workers of a sweep)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        if os.getpgid(p.pid) == p.pid:
            os.killpg(p.pid, signal.SIGKILL)
        else:
            p.kill()


def finish(p: subprocess.Popen, t0: float, timeout: float) -> Result:
    try:
        out, err = p.communicate(timeout=max(1.0, timeout - (time.monotonic() - t0)))
        res = Result(p.returncode, out, err, time.monotonic() - t0)
    except subprocess.TimeoutExpired:
        kill_group(p)
        out, err = p.communicate()
        res = Result(None, out, err, time.monotonic() - t0, timed_out=True)
    kill_group(p)                       # leftovers of the group (e.g. Dask workers)
    return res


def run_subprocess(ctx: Ctx, argv: Sequence[str], timeout: float,
                   extra_pre: Sequence[Callable] = ()) -> Result:
    t0 = time.monotonic()
    p = popen(ctx, argv, extra_pre)
    return finish(p, t0, timeout)


def run_inprocess(argv: Sequence[str]) -> Result:
    """``kvrod.cli.main(argv)`` with stdout/stderr captured; an escaping exception is what a
    user would see as a traceback."""
    import traceback

    from kvrod.cli import main

    out, err = io.StringIO(), io.StringIO()
    t0 = time.monotonic()
    escaped = ""
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(list(argv))
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        except BaseException as exc:  # noqa: BLE001 - a traceback for the user
            rc = None
            escaped = f"{type(exc).__name__}: {exc}"
            err.write("Traceback (most recent call last):\n" + traceback.format_exc())
    return Result(rc, out.getvalue(), err.getvalue(), time.monotonic() - t0, escaped)


def wait_for(pred: Callable[[], bool], timeout: float, p: subprocess.Popen | None = None,
             step: float = 0.02) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        with contextlib.suppress(OSError, ValueError):
            if pred():
                return True
        if p is not None and p.poll() is not None:
            return False
        time.sleep(step)
    return False


# --------------------------------------------------------------------------------------
# templates: results folders built once per session and copied into cases
# --------------------------------------------------------------------------------------

SIM = ("simulate", "cantilever", "--n-elements", "4", "--t-end", "0.2")
MODES = ("modes", "cantilever", "--n-elements", "4", "--count", "2")
KILLED_T_END = "8"
KILLED = ("simulate", "cantilever", "--n-elements", "4", "--t-end", KILLED_T_END)
DELTAS = "delta\n0.45\n0.44\n0.46\n"
#: a generalized Maxwell run long enough to be killed after its first checkpoint
MAXWELL_KILLED = ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "2000")


class Templates:
    """Results folders of finished / killed / failed runs, modes, calibration and a study,
    made by the CLI itself (in-process, or a real SIGKILL for the killed run)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._made: dict[str, Path] = {}

    def get(self, key: str) -> Path:
        if key not in self._made:
            path = self.root / key
            getattr(self, f"_make_{key}")(path)
            self._made[key] = path
        return self._made[key]

    @staticmethod
    def _cli(argv: Sequence[str], ok: tuple = (0,)) -> None:
        r = run_inprocess(argv)
        assert r.rc in ok, f"template {argv}: exit {r.rc}: {r.stderr[-2000:]}"

    def _make_finished(self, path: Path) -> None:
        # two maxima -> damping_ratio.png; VTK every 0.5 s -> vtk/
        self._cli(["simulate", "cantilever", "--n-elements", "4", "--t-end", "2", "--vtk", "0.5",
                   "--plots", "--out", str(path)])
        assert (path / "damping_ratio.png").exists() and (path / "vtk" / "rod.pvd").exists()

    def _make_failed(self, path: Path) -> None:
        cfg = self.root / "failing.toml"
        cfg.write_text('scenario = "cantilever"\n[parameters]\nn_elements = 4\nt_end = 1.0\n'
                       "min_step = 0.2\n")
        self._cli(["simulate", "--config", str(cfg), "--out", str(path)], ok=(1,))
        assert (summary := read_json(path / "summary.json")) and summary["status"] == "failed"

    def _make_killed(self, path: Path, extra: Sequence[str] = ()) -> None:
        """A run SIGKILLed after its first checkpoint: summary "running" + checkpoint.npz
        (``extra``: more flags, or a whole command line when it starts with "simulate")."""
        # a checkpoint at the first simulated second, however short the run's wall time
        ctx = Ctx(tmp=self.root, out=path, env={"KVROD_CHECKPOINT_WALL": "0"})
        argv = list(extra) if extra[:1] == ("simulate",) else [*KILLED, *extra]
        for _ in range(5):
            shutil.rmtree(path, ignore_errors=True)
            p = popen(ctx, [*argv, "--out", str(path)])
            wait_for(lambda: (path / "checkpoint.npz").exists(), 60, p, step=0.005)
            with contextlib.suppress(ProcessLookupError):
                p.send_signal(signal.SIGKILL)
            p.communicate()
            s = read_json(path / "summary.json")
            if (path / "checkpoint.npz").exists() and s and s.get("status") == "running":
                return
        raise AssertionError("could not produce a killed run with a checkpoint")

    def _make_killed_maxwell(self, path: Path) -> None:
        """A generalized Maxwell run (internal strains in its state) SIGKILLed after its
        first checkpoint."""
        self._make_killed(path, MAXWELL_KILLED)

    def _make_killed_vtk(self, path: Path) -> None:
        """A run with VTK output every second, SIGKILLed after its first checkpoint."""
        self._make_killed(path, ("--vtk", "1"))

    def _make_interrupted(self, path: Path) -> None:
        shutil.copytree(self.get("killed"), path)
        s = read_json(path / "summary.json")
        s["status"], s["message"] = "interrupted", "interrupted by the user (SIGINT)"
        (path / "summary.json").write_text(json.dumps(s, indent=2) + "\n")

    def _make_modes(self, path: Path) -> None:
        self._cli([*MODES, "--out", str(path)])

    def _make_calibration(self, path: Path) -> None:
        d = self.root / "deltas.csv"
        d.write_text(DELTAS)
        self._cli(["calibrate", "--mode", "decrements", "--data", str(d), "--n-elements", "4",
                   "--out", str(path)])

    def _make_section(self, path: Path) -> None:
        f = self.root / "section_ok.toml"
        f.write_text(SECTION_OK)
        self._cli(["section", str(f), "--out", str(path)])
        assert (path / "section.json").exists() and (path / "section.png").exists()

    def _make_static(self, path: Path) -> None:
        self._cli(["static", "cantilever", "--n-elements", "4", "--out", str(path)])
        assert (path / "static.npz").exists()

    def _make_sweep(self, path: Path) -> None:
        st = self.root / "study_ok.toml"
        st.write_text(STUDY_OK)
        self._cli(["sweep", str(st), "--serial", "--out", str(path)])


# --------------------------------------------------------------------------------------
# setups (callables of ctx)
# --------------------------------------------------------------------------------------


def template(key: str) -> Callable:
    def setup(ctx: Ctx) -> None:
        shutil.copytree(ctx.templates.get(key), ctx.out)
    setup.__name__ = f"template_{key}"
    return setup


def write(name: str, text: str | bytes) -> Callable:
    def setup(ctx: Ctx) -> None:
        p = ctx.tmp / name
        p.parent.mkdir(parents=True, exist_ok=True)
        (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
    return setup


def in_out(name: str, text: str) -> Callable:
    """A file of the user's own in the results folder (after a template made it)."""
    def setup(ctx: Ctx) -> None:
        ctx.out.mkdir(parents=True, exist_ok=True)
        (ctx.out / name).write_text(text)
    return setup


def config(text: str) -> Callable:
    return write("run.toml", 'scenario = "cantilever"\n' + text)


def study(text: str) -> Callable:
    return write("study.toml", text)


def out_is_file(ctx: Ctx) -> None:
    ctx.out = ctx.tmp / "afile"
    ctx.out.write_text("precious data, not a results folder\n")


def long_out(ctx: Ctx) -> None:
    ctx.out = ctx.tmp / ("x" * 300)


def deep_out(ctx: Ctx) -> None:
    ctx.out = ctx.tmp.joinpath(*(["d" * 200] * 22))


def readonly_parent(ctx: Ctx) -> None:
    ro = ctx.tmp / "readonly_dir"
    ro.mkdir()
    ctx.out = ro / OUT_NAME
    ro.chmod(0o555)
    ctx.preexec.append(drop_dac)


def checkpoint_bytes(fn: Callable[[bytes], bytes]) -> Callable:
    def setup(ctx: Ctx) -> None:
        p = ctx.out / "checkpoint.npz"
        p.write_bytes(fn(p.read_bytes()))
    return setup


def checkpoint_arrays(fn: Callable[[dict], dict]) -> Callable:
    """Rewrite the checkpoint with arrays changed by ``fn`` (a valid NPZ, bad content)."""
    def setup(ctx: Ctx) -> None:
        p = ctx.out / "checkpoint.npz"
        with np.load(p) as f:
            arrays = {k: f[k] for k in f.files}
        arrays = fn(arrays)
        tmp = ctx.tmp / "ck.npz"
        np.savez_compressed(tmp, **arrays)
        shutil.move(tmp, p)
    return setup


def checkpoint_is_dir(ctx: Ctx) -> None:
    p = ctx.out / "checkpoint.npz"
    p.unlink()
    p.mkdir()


def _sleeper(ctx: Ctx) -> subprocess.Popen:
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"],
                         start_new_session=True)
    ctx.procs.append(p)
    return p


def live_lock(ctx: Ctx) -> None:
    """Another (live) process holds the folder's lock."""
    holder = _sleeper(ctx)
    ctx.out.mkdir(parents=True, exist_ok=True)
    data = json.dumps({"pid": holder.pid}).encode()
    (ctx.out / LOCK_NAME).write_bytes(data)
    ctx.planted_lock = data
    ctx.vars["pid"] = str(holder.pid)


def stale_lock(ctx: Ctx) -> None:
    """A lock left by a process that no longer exists."""
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    ctx.out.mkdir(parents=True, exist_ok=True)
    (ctx.out / LOCK_NAME).write_text(json.dumps({"pid": p.pid}))
    ctx.vars["pid"] = str(p.pid)


def decay_record() -> tuple[np.ndarray, np.ndarray]:
    """(t, x) of the synthetic decay record (t in s since release, x in m)."""
    rows = [ln.split(",") for ln in DATA.read_text().splitlines()
            if ln.strip() and not ln.startswith("#")]
    assert rows[0] == ["t", "x"], rows[0]
    a = np.array(rows[1:], dtype=float)
    return a[:, 0], a[:, 1]


def data_file(name: str, fn: Callable[[np.ndarray, np.ndarray], tuple]) -> Callable:
    """A decay record derived from the synthetic one (t in s, x in m) by ``fn(t, x)``."""
    def setup(ctx: Ctx) -> None:
        t, x = decay_record()
        t2, x2 = fn(t, x)
        lines = ["t,x", *(f"{a:.6g},{b:.6e}" for a, b in zip(t2, x2, strict=True))]
        (ctx.tmp / name).write_text("\n".join(lines) + "\n")
        ctx.vars["data_name"] = name
    return setup


def _noise(t: np.ndarray, x: np.ndarray) -> tuple:
    rng = np.random.default_rng(3)
    tt = t[t <= 1.0]
    return tt, 0.05 * rng.standard_normal(tt.size)


def generated_copy(mutate: Callable[[Path], None]) -> Callable:
    """A copy of generated/ first on PYTHONPATH, changed by ``mutate(folder)``."""
    def setup(ctx: Ctx) -> None:
        import generated

        src = Path(generated.__file__).resolve().parent
        dst = ctx.tmp / "gen" / "generated"
        shutil.copytree(src, dst, ignore=shutil.ignore_patterns("__pycache__"))
        mutate(dst)
        ctx.pythonpath.insert(0, str(ctx.tmp / "gen"))
        ctx.env["KVROD_CACHE_DIR"] = str(ctx.tmp / "cache")
    return setup


def _edit_constitutive(g: Path) -> None:
    """tau_E x 1.5: a plausible hand edit of a formula module (not of the C sources)."""
    with open(g / "constitutive.py", "a") as fh:
        fh.write("\n\n_orig_tau_E = retardation_time_extension\n\n\n"
                 "def retardation_time_extension(tau_B, tau_S, nu):  # edited by hand\n"
                 "    return 1.5 * _orig_tau_E(tau_B, tau_S, nu)\n")


def series_bytes(fn: Callable[[bytes], bytes]) -> Callable:
    def setup(ctx: Ctx) -> None:
        p = ctx.out / "series.npz"
        p.write_bytes(fn(p.read_bytes()))
    return setup


def _reshaped_series(data: bytes) -> bytes:
    """A valid NPZ whose tip history is shorter than its time axis."""
    with np.load(io.BytesIO(data)) as f:
        arrays = {k: f[k] for k in f.files}
    arrays["tip"] = arrays["tip"][:, :3]
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def points_problem(points: str | None = None, file: str | None = None) -> Callable:
    """{tmp}/rod.toml: a clamped-free rod through the given points (or a points file)."""
    geo = f"points = {points}\n" if points is not None else f'file = "{file}"\n'
    return write("rod.toml", '[rod]\nelements = 8\n[rod.geometry]\nkind = "points"\n' + geo
                 + '[section]\nkind = "circle"\nradius = 0.005\n[simulation]\nt_end = 0.1\n')


def _noisy(level: float, seed: int = 11) -> Callable:
    def fn(t: np.ndarray, x: np.ndarray) -> tuple:
        rng = np.random.default_rng(seed)
        return t, x + level * rng.standard_normal(x.size)
    return fn


def _edit_kernel(g: Path) -> None:
    with open(g / "rod_kernels.c", "a") as fh:
        fh.write("\n/* edited by hand */\n")


def _truncate_manifest(g: Path) -> None:
    m = g / "MANIFEST.json"
    m.write_bytes(m.read_bytes()[: len(m.read_bytes()) // 2])


def _remove_manifest(g: Path) -> None:
    (g / "MANIFEST.json").unlink()


# --------------------------------------------------------------------------------------
# checks (callables of ctx, result -> failure text or None)
# --------------------------------------------------------------------------------------


def UNCHANGED(ctx: Ctx, r: Result) -> str | None:
    after = snapshot(ctx.out)
    if after == ctx.snapshot:
        return None
    before = ctx.snapshot or {}
    now = after or {}
    changed = sorted(k for k in set(before) | set(now) if before.get(k) != now.get(k))
    return f"results folder changed: {changed[:8]}"


def ABSENT(ctx: Ctx, r: Result) -> str | None:
    return None if not lexists(ctx.out) else (
        f"results folder was created: {sorted(snapshot(ctx.out) or {})[:6]}")


def status(*values: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        s = summary_of(ctx)
        got = None if s is None else s.get("status")
        return None if got in values else f"summary status {got!r}, expected one of {values}"
    return check


def has(*names: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        missing = [n for n in names if not lexists(ctx.out / n)]
        return f"missing in the results folder: {missing}" if missing else None
    return check


def lacks(*names: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        there = [n for n in names if lexists(ctx.out / n)]
        return f"left over in the results folder: {there}" if there else None
    return check


def summary_is(pred: Callable[[dict], bool], what: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        s = summary_of(ctx)
        try:
            ok = s is not None and pred(s)
        except (KeyError, TypeError, ValueError, IndexError):
            ok = False
        return None if ok else f"summary.json: expected {what}"
    return check


def json_is(name: str, pred: Callable[[dict], bool], what: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        d = read_json(ctx.out / name)
        try:
            ok = d is not None and pred(d)
        except (KeyError, TypeError, ValueError, IndexError):
            ok = False
        return None if ok else f"{name}: expected {what}"
    return check


def stdout_has(*words: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        missing = [w for w in words if w not in r.stdout]
        return f"stdout lacks {missing}" if missing else None
    return check


def stdout_lacks(*words: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        there = [w for w in words if w in r.stdout]
        return f"stdout has {there}" if there else None
    return check


def _ss_reference() -> tuple[float, float]:
    """Midspan sag (m) and first bending omega (rad/s) of examples/simply_supported.toml
    (references/supported.py, from the file's numbers)."""
    import tomllib

    from references import examples as RX

    doc = tomllib.loads((ROOT / "examples" / "simply_supported.toml").read_text())
    ref = RX.simply_supported_reference(doc)
    return ref["midspan"], float(ref["frequencies"]["bending-1"][0])


SS = ("static", "simply_supported")
SS_SAG, SS_OMEGA = _ss_reference()


def _ss_modes_ok(d: dict) -> bool:
    m0, m1 = d["modes"][0], d["modes"][1]
    return (m0["family"] == "rigid" and m0["omega"] == 0 and m0["zeta"] is None
            and m1["family"].startswith("bending") and abs(m1["omega"] / SS_OMEGA - 1) < 5e-3)


def not_running(ctx: Ctx, r: Result) -> str | None:
    s = summary_of(ctx)
    if s is not None and s.get("status") == "running":
        return "a stopped run's summary.json still says 'running'"
    return None


def _num(v) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _warned(ctx: Ctx, r: Result) -> bool:
    s = summary_of(ctx) or {}
    lines = [ln for ln in stderr_lines(r.stderr) if ln.lower().startswith("kvrod: warning:")]
    w = s.get("warnings")
    return bool(lines) and isinstance(w, list) and bool(w) and all(isinstance(x, str) for x in w)


def accurate_or_warned(need_positive_decrements: bool = False) -> Check:
    """Spec 9: an energy audit error above ENERGY_WARN (or, for a damped rod, a negative log
    decrement) is only acceptable with a `kvrod: warning:` line and summary["warnings"]."""
    def check(ctx: Ctx, r: Result) -> str | None:
        s = summary_of(ctx)
        if s is None:
            return "no summary.json"
        eb = _num(s.get("energy_balance_max_rel"))
        bad = []
        if eb is not None and eb > ENERGY_WARN:
            bad.append(f"energy audit error {eb:.3g}")
        dec = [v for v in s.get("log_decrements") or [] if _num(v) is not None]
        if need_positive_decrements and any(v <= 0 for v in dec):
            bad.append(f"log decrements {[round(v, 5) for v in dec[:6]]} not all > 0")
        if bad and not _warned(ctx, r):
            return ("doubtful result reported without a 'kvrod: warning:' line and "
                    "summary['warnings']: " + "; ".join(bad))
        return None
    return check


def no_false_warning(ctx: Ctx, r: Result) -> str | None:
    lines = [ln for ln in stderr_lines(r.stderr) if "warning" in ln.lower()]
    w = (summary_of(ctx) or {}).get("warnings")
    if lines or w:
        return f"a clean run was warned about: {lines or w}"
    return None


def energy_not_applicable(ctx: Ctx, r: Result) -> str | None:
    s = summary_of(ctx)
    if s is None:
        return "no summary.json"
    eb = s.get("energy_balance_max_rel")
    v = _num(eb)
    if v is not None and v > ENERGY_WARN:
        return f"energy audit error {v:.3g} reported for a release from zero energy"
    if eb is not None and v is None and not isinstance(eb, str):
        return f"energy_balance_max_rel = {eb!r}"
    if re.search(r"energy balance max rel\. error: *\d", r.stdout) and v is not None and v > 0:
        return "stdout reports a relative energy error for a zero reference energy"
    return None


def pvd_covers(t_end: float, dt: float) -> Check:
    """vtk/rod.pvd holds frames from t = 0 to t_end, no gap wider than dt."""
    def check(ctx: Ctx, r: Result) -> str | None:
        p = ctx.out / "vtk" / "rod.pvd"
        if not p.exists():
            return "no vtk/rod.pvd"
        ts = pvd_times(p)
        if not ts:
            return "vtk/rod.pvd has no frames"
        gaps = np.diff(ts)
        if (abs(ts[0]) > 1e-12 or ts[-1] < t_end - dt * 1.001 or np.any(gaps <= 0)
                or np.any(gaps > dt * 1.001)):
            return (f"vtk/rod.pvd frames {len(ts)} at t = {ts[0]:.4g} ... {ts[-1]:.4g}; "
                    f"expected 0 ... {t_end} every {dt}")
        for k in range(len(ts)):
            if not (ctx.out / "vtk" / f"rod_{k:05d}.vtp").exists():
                return f"vtk/rod_{k:05d}.vtp missing"
        return None
    return check


def series_covers(t_end: float) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        try:
            with np.load(ctx.out / "series.npz") as f:
                t = f["t"]
        except (OSError, ValueError, KeyError) as exc:
            return f"series.npz unreadable: {exc}"
        if t.size == 0 or t[0] != 0.0 or abs(t[-1] - t_end) > 1e-9 or np.any(np.diff(t) <= 0):
            return f"series.npz t = {t[:1]} ... {t[-1:]} (expected 0 ... {t_end}, increasing)"
        return None
    return check


def csv_has(pred: Callable[[list], bool], what: str) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        p = ctx.out / "study.csv"
        if not p.exists():
            return "no study.csv"
        rows = read_rows(p)
        try:
            ok = pred(rows)
        except (KeyError, ValueError, IndexError):
            ok = False
        return None if ok else f"study.csv: expected {what}; statuses " \
                               f"{[row.get('status') for row in rows][:8]}"
    return check


def calibration_verdict(ctx: Ctx, r: Result) -> str | None:
    """Exit 1: calibration.json kept and marked failed; exit 2: nothing written."""
    if r.rc == 0:
        d = read_json(ctx.out / "calibration.json") or {}
        ci = d.get("ci95") or ["?", "?"]
        return f"fit accepted: tau = {d.get('tau')!r} s, 95 % CI {ci}"
    if r.rc == 2:
        return ABSENT(ctx, r)
    if r.rc == 1:
        d = read_json(ctx.out / "calibration.json")
        if d is None:
            return "exit 1 but no calibration.json (the fit that was computed is lost)"
        if not (d.get("status") == "failed" or d.get("success") is False):
            return f"calibration.json of a rejected fit: status {d.get('status')!r}, " \
                   f"success {d.get('success')!r}"
    return None


def tau_near(value: float, rel: float) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        d = read_json(ctx.out / "calibration.json")
        if d is None:
            return "no calibration.json"
        tau, ci = d.get("tau"), d.get("ci95") or [math.nan, math.nan]
        if not (abs(tau / value - 1) <= rel and ci[0] > 0 and ci[0] <= tau <= ci[1]):
            return f"tau = {tau}, CI {ci}; expected {value} +- {rel:.0%} with a CI above 0"
        return None
    return check


def elapsed_below(seconds: float) -> Check:
    def check(ctx: Ctx, r: Result) -> str | None:
        return None if r.elapsed < seconds else f"took {r.elapsed:.1f} s (limit {seconds} s)"
    return check


def no_text(*words: str) -> Check:
    """None of ``words`` in stdout or stderr (e.g. a NumPy repr such as np.float64)."""
    def check(ctx: Ctx, r: Result) -> str | None:
        found = [w for w in words if w in r.stdout + r.stderr]
        return f"the output shows {found}" if found else None
    return check


def summary_loads(n: int) -> Check:
    return summary_is(lambda s: len(s["parameters"]["loads"]) == n, f"{n} loads")


def checkpoint_kept(ctx: Ctx, r: Result) -> str | None:
    return None if (ctx.out / "checkpoint.npz").exists() else "checkpoint.npz was removed"


# --------------------------------------------------------------------------------------
# custom runs (signals, two processes, repetition)
# --------------------------------------------------------------------------------------

# "long": runs that a test interrupts must outlast it by far (the compiled step loop
# integrates the 4-element rod at about 1000 simulated seconds per wall second)
LONG_SIM = ("simulate", "cantilever", "--n-elements", "4", "--t-end", "20000")


def _csv_text(ctx: Ctx) -> str:
    p = ctx.out / "study.csv"
    return p.read_text() if p.exists() else ""


def run_signal_simulate(sig: int, group: bool) -> Callable[[Ctx], Result]:
    """A long simulation, stopped by ``sig`` after its first checkpoint (Ctrl-C: the group)."""
    def run(ctx: Ctx) -> Result:
        t0 = time.monotonic()
        p = popen(ctx, [*LONG_SIM, "--out", str(ctx.out)])
        if not wait_for(lambda: (ctx.out / "checkpoint.npz").exists(), 90, p):
            return finish(p, t0, 1)
        time.sleep(0.3)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, sig) if group else p.send_signal(sig)
        return finish(p, t0, 90)
    return run


def run_second_simulate(ctx: Ctx) -> Result:
    """Process A runs on the folder; process B (a short run) is started on the same folder."""
    a = popen(ctx, [*LONG_SIM, "--out", str(ctx.out)])
    ctx.vars["pid"] = str(a.pid)
    try:
        if not wait_for(lambda: (ctx.out / "checkpoint.npz").exists(), 90, a):
            return Result(None, *a.communicate(), escaped="process A ended early")
        res = run_subprocess(ctx, [*SIM, "--out", str(ctx.out)], 60)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(a.pid, signal.SIGINT)
        finish(a, time.monotonic(), 60)
    return res


STUDY_OK = """scenario = "cantilever"
[fixed]
n_elements = 4
t_end = 0.2
[grid]
tau = [0.02, 0.04]
"""

STUDY_LONG = """scenario = "cantilever"
[fixed]
n_elements = 4
[grid]
t_end = [20000.0, 20001.0]
"""

STUDY_SHORT_THEN_LONG = """scenario = "cantilever"
[fixed]
n_elements = 4
[grid]
t_end = [0.2, 20000.0]
"""

STUDY_DASK_LONG = """scenario = "cantilever"
[fixed]
n_elements = 4
t_end = 20000.0
[grid]
tau = [0.02, 0.04, 0.06, 0.08]
"""


def _progress(ctx: Ctx) -> dict:
    """The sweep's live counts (DIR/progress.json), {} before it exists."""
    return read_json(ctx.out / "progress.json") or {}


def run_two_sweeps(ctx: Ctx) -> Result:
    """Sweep A (serial, long points) writes the folder; sweep B is started on it."""
    (ctx.tmp / "a.toml").write_text(STUDY_LONG)
    (ctx.tmp / "b.toml").write_text(STUDY_OK)
    a = popen(ctx, ["sweep", str(ctx.tmp / "a.toml"), "--serial", "--out", str(ctx.out)])
    ctx.vars["pid"] = str(a.pid)
    try:
        if not wait_for(lambda: _progress(ctx).get("running", 0) > 0, 90, a):
            return Result(None, *a.communicate(), escaped="sweep A ended early")
        res = run_subprocess(ctx, ["sweep", str(ctx.tmp / "b.toml"), "--serial",
                                   "--out", str(ctx.out)], 60)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(a.pid, signal.SIGINT)
        finish(a, time.monotonic(), 60)
    return res


def run_sweep_sigint(serial: bool) -> Callable[[Ctx], Result]:
    def run(ctx: Ctx) -> Result:
        text = STUDY_SHORT_THEN_LONG if serial else STUDY_DASK_LONG
        (ctx.tmp / "study.toml").write_text(text)
        extra = ["--serial"] if serial else ["--workers", "2"]
        t0 = time.monotonic()
        p = popen(ctx, ["sweep", str(ctx.tmp / "study.toml"), *extra, "--out", str(ctx.out)])
        if serial:
            ready = wait_for(lambda: "finished" in _csv_text(ctx)
                             and _progress(ctx).get("running", 0) > 0, 90, p)
        else:
            ready = wait_for(lambda: _progress(ctx).get("running", 0) > 0, 120, p)
        if not ready:
            return finish(p, t0, 1)
        time.sleep(1.0)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGINT)                 # Ctrl-C: the whole group
        return finish(p, t0, 120)
    return run


def run_modes_repeatedly(ctx: Ctx, times: int = 12, budget: float = 30.0) -> Result:
    """The same modal analysis, in-process, up to ``times`` runs: the first failure counts."""
    t0 = time.monotonic()
    res = Result(None)
    for i in range(times):
        ctx.out = ctx.tmp / f"{OUT_NAME}{i}"
        res = run_inprocess(["modes", "cantilever", "--n-elements", "80", "--count", "2",
                             "--out", str(ctx.out)])
        res.info = f"run {i + 1} of up to {times}"
        if res.rc != 0 or time.monotonic() - t0 > budget:
            break
    res.elapsed = time.monotonic() - t0
    return res


# --------------------------------------------------------------------------------------
# issue 30: round-off plies, signals during a section analysis and a fit, damaged files
# --------------------------------------------------------------------------------------

#: two plies written with decimal centres: after round-off they overlap by 8.7e-19 m, and
#: the mesher refined the sliver between their edges without end (60 MB/s, deaf to Ctrl-C)
PLIES = """name = "plies"
[section]
kind = "composite"
[[section.regions]]
name = "bottom"
material = "a"
shape = { kind = "rectangle", width = 0.02, height = 0.005, centre = [0, 0.0025] }
[[section.regions]]
name = "top"
material = "b"
shape = { kind = "rectangle", width = 0.02, height = 0.005, centre = [0, 0.0075] }
[materials.a]
youngs_modulus = 1e9
poisson_ratio = 0.3
density = 1000.0
[materials.b]
youngs_modulus = 2e9
poisson_ratio = 0.35
density = 1200.0
tau_S = 0.01
"""
#: the plies as the section of a cantilever
PLIES_ROD = ("[rod]\nlength = 0.3\nelements = 4\n" + PLIES.replace('name = "plies"\n', "")
             + '[[loads]]\nkind = "force"\nat = "end"\nvector = [0.01, 0.0, 0.0]\n')


def run_signal_section(sig: int, argv: Sequence[str]) -> Callable[[Ctx], Result]:
    """``kvrod section ...`` (a long analysis: --tol 1e-9) sent ``sig`` (to its group, as
    Ctrl-C) two seconds after it locked its folder, i.e. inside the analysis (past the
    imports: a KeyboardInterrupt inside some extension's import makes Python end by
    SIGINT, returncode -2, even when kvrod caught it); ``elapsed`` is the time from the
    signal to the exit."""
    def run(ctx: Ctx) -> Result:
        p = popen(ctx, [ctx.fmt(a) for a in argv])
        if not wait_for(lambda: (ctx.out / LOCK_NAME).exists(), 90, p):
            return finish(p, time.monotonic(), 1)
        time.sleep(2.0)
        t_signal = time.monotonic()
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, sig)
        return finish(p, t_signal, 60)
    return run


def _long_decay_text(T: float = 1.8176, zeta: float = 0.002, x0: float = 0.2217,
                     span: float = 300.0, dt: float = 0.05) -> str:
    """A lightly damped release record, 165 periods long (t in s since the release, x in
    m; the model cantilever's period and release deflection at N = 4): each model
    evaluation of a fit simulates 300 s, so a Ctrl-C lands in the compiled step loop."""
    wd = 2 * math.pi / T
    w = wd / math.sqrt(1 - zeta * zeta)
    t = np.arange(int(round(span / dt)) + 1) * dt
    x = x0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    return "t,x\n" + "".join(f"{a:.6g},{b:.6e}\n" for a, b in zip(t, x, strict=True))


def run_signal_calibrate(sig: int, delay: float = 8.0) -> Callable[[Ctx], Result]:
    """``kvrod calibrate`` on the long record, sent ``sig`` (its group) after ``delay`` s,
    inside a model simulation."""
    def run(ctx: Ctx) -> Result:
        (ctx.tmp / "long.csv").write_text(_long_decay_text())
        t0 = time.monotonic()
        p = popen(ctx, ["calibrate", "--data", str(ctx.tmp / "long.csv"), "--n-elements",
                        "16", "--out", str(ctx.out)])
        time.sleep(delay)
        if p.poll() is not None:
            return finish(p, t0, 1)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, sig)
        return finish(p, t0, 90)
    return run


def npz_bytes(name: str, fn: Callable[[bytes], bytes]) -> Callable:
    def setup(ctx: Ctx) -> None:
        p = ctx.out / name
        p.write_bytes(fn(p.read_bytes()))
    return setup


def _still_start(t: np.ndarray, x: np.ndarray) -> tuple:
    """The record preceded by half a second at rest: the release is at t = 0.5 s."""
    before = np.arange(0.0, 0.5, t[1] - t[0])
    return np.concatenate([before, t + 0.5]), np.concatenate([np.full(before.size, x[0]), x])


# --------------------------------------------------------------------------------------
# the table
# --------------------------------------------------------------------------------------

OUT = ("--out", "{out}")
OVR = (OVERWRITE_FLAG,)
CAL_D = ("calibrate", "--mode", "decrements", "--data", "{tmp}/delta.csv", "--n-elements", "4")
CAL_S = ("calibrate", "--data", "{data}", "--n-elements", "4")
SWEEP = ("sweep", "{tmp}/study.toml", "--serial")
DELTA = write("delta.csv", DELTAS)
#: a small composite section file (two regions) and variants of it
SECTION_OK = """name = "two_layers"
[section]
kind = "composite"
[[section.regions]]
material = "core"
shape = { kind = "circle", radius = 0.001 }
[[section.regions]]
material = "sheath"
shape = { kind = "tube", inner_radius = 0.001, outer_radius = 0.002 }
[materials.core]
youngs_modulus = 1e11
poisson_ratio = 0.3
density = 8000.0
[materials.sheath]
youngs_modulus = 1e7
poisson_ratio = 0.45
density = 1200.0
tau_S = 0.01
"""
SEC = ("section", "{tmp}/sec.toml")
#: the composite's sheath as a generalized Maxwell material (refused in a composite)
MAXWELL_REGION = (SECTION_OK.replace('name = "two_layers"', "")
                  .replace("[materials.sheath]\n", '[materials.sheath]\nmodel = '
                           '"generalized_maxwell"\n')
                  .replace("tau_S = 0.01\n", "[[materials.sheath.branches]]\n"
                           "youngs_modulus = 1e6\npoisson_ratio = 0.45\ntau = 0.01\n"))


def section_file(old: str = "", new: str = "") -> Callable:
    """SECTION_OK with ``old`` replaced by ``new`` (all must change), as {tmp}/sec.toml."""
    text = SECTION_OK.replace(old, new) if old else SECTION_OK
    assert text != SECTION_OK or not old, old
    return write("sec.toml", text)


SPD_BAD = ('[materials.sheath]\nyoungs_modulus = 1e7\npoisson_ratio = 0.45\n'
           'density = 1200.0\ntau_S = 0.01\n',
           '[materials.sheath]\ndensity = 1200.0\nstiffness_matrix = ['
           + ", ".join("[" + ", ".join(("-1e9" if i == j == 2 else "1e9" if i == j else "0.0")
                                       for j in range(6)) + "]" for i in range(6)) + "]\n")
FOLDER = ("{out_name}",)
GUARDED = {"guard": True}
#: the contact radius of the square cantilever (which has no outer radius) and a floor
#: 1 m below its clamp (issue 32)
CONTACT_R = "contact.radius=0.005"
FLOOR = 'obstacles.0={{kind="plane", point=[0,0,-1], normal=[0,0,1]}}'

#: reasons a rejected calibration may give (spec 8), by data defect
WHY_UNITS = ("unit", "scale", "residual", "amplitude", "magnitude", "mm", "metre", "meter")
WHY_SIGN = ("sign", "negative", "flip", "residual", "phase", "invert")
WHY_SPAN = ("span", "time", "unit", "ms", "second", "duration", "long")
WHY_FIT = ("residual", "confidence", "ci", "noise", "zero", "signal", "fit")
DATA_NAMED = ("{data_name}", "--data", "data")

CASES: list[Case] = [
    # ==================================================================================
    # data_loss: a results folder holding a finished result, validation before writing,
    # --overwrite, --resume, the lock, stopped runs
    # ==================================================================================
    Case("simulate-rtol-1e-14-after-finished-run-keeps-it", "data_loss",
         (*SIM, "--rtol", "1e-14", *OUT), 2, ("rtol", "range"),
         (template("finished"),), (UNCHANGED,), note="issue: rewrote summary to running"),
    Case("simulate-rtol-1e-14-creates-no-folder", "data_loss",
         (*SIM, "--rtol", "1e-14", *OUT), 2, ("rtol", "range"), (), (ABSENT,)),
    Case("simulate-rtol-1e-14-with-overwrite-keeps-old-run", "data_loss",
         (*SIM, "--rtol", "1e-14", *OVR, *OUT), 2, ("rtol",),
         (template("finished"),), (UNCHANGED,)),
    Case("simulate-t-end-1e300-after-finished-run-keeps-it", "data_loss",
         (*SIM[:-1], "1e300", *OUT), 2, ("t_end", RANGE), (template("finished"),), (UNCHANGED,)),
    Case("simulate-nu-0.7-after-finished-run-keeps-it", "data_loss",
         (*SIM, "--nu", "0.7", *OUT), 2, ("poisson_ratio", "range"),
         (template("finished"),), (UNCHANGED,)),
    Case("simulate-bad-config-after-finished-run-keeps-it", "data_loss",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("tua",),
         (template("finished"), config("[parameters]\ntua = 0.04\n")), (UNCHANGED,)),
    Case("simulate-new-params-into-finished-run-refused", "data_loss",
         (*SIM, "--tau", "0.08", *OUT), 2, (*FOLDER, OVERWRITE_FLAG, "--resume"),
         (template("finished"),), (UNCHANGED,), note="issue: old plots/vtk left beside"),
    Case("simulate-same-params-into-finished-run-refused", "data_loss",
         (*SIM[:-1], "2", *OUT), 2, (*FOLDER, OVERWRITE_FLAG, "--resume"),
         (template("finished"),), (UNCHANGED,)),
    Case("simulate-into-failed-run-refused", "data_loss",
         (*SIM, *OUT), 2, (*FOLDER, OVERWRITE_FLAG, "--resume"), (template("failed"),),
         (UNCHANGED,)),
    Case("simulate-into-interrupted-run-refused", "data_loss",
         (*SIM, *OUT), 2, (*FOLDER, OVERWRITE_FLAG, "--resume"),
         (template("interrupted"),), (UNCHANGED,)),
    Case("simulate-overwrite-removes-old-plots-and-vtk", "data_loss",
         (*SIM, *OVR, *OUT), 0, (), (template("finished"),),
         (status("finished"), lacks("vtk", "damping_ratio.png", "checkpoint.npz"),
          summary_is(lambda s: s["parameters"]["simulation"]["t_end"] == 0.2,
                     "the new run's t_end 0.2"),
          series_covers(0.2))),
    Case("simulate-overwrite-keeps-the-users-pictures", "data_loss",
         (*SIM, *OVR, *OUT), 0, (), (template("finished"), in_out("my_photo.png", "mine"),
                                     in_out("sketch.gif", "mine")),
         (status("finished"), has("my_photo.png", "sketch.gif"), lacks("damping_ratio.png")),
         note="--overwrite removed every *.png, *.gif, *.mp4 of the folder"),
    Case("simulate-overwrite-keeps-a-section-result-beside-it", "data_loss",
         (*SIM, *OVR, *OUT), 0, (), (template("section"),),
         (status("finished"), has("section.json", "section.png")),
         note="section.png (not redrawable: its mesh is not stored) went, section.json stayed"),
    Case("static-overwrite-of-a-run-leaves-no-run-series", "wrong_answer",
         ("static", "cantilever", "--n-elements", "4", *OVR, *OUT), 0, (),
         (template("finished"),),
         (has("summary.json", "static.npz"), lacks("series.npz", "vtk", "damping_ratio.png")),
         note="the run's series.npz stayed beside the static summary: kvrod plot drew the "
              "old run as the folder's result"),
    Case("modes-overwrite-keeps-a-run-beside-it", "data_loss",
         (*MODES, "--plots", *OVR, *OUT), 0, (), (template("finished"),),
         (has("modes.json", "mode_shapes.png", "damping_ratio.png", "series.npz"),)),
    Case("simulate-overwrite-replaces-killed-run-and-checkpoint", "data_loss",
         (*SIM, *OVR, *OUT), 0, (), (template("killed"),),
         (status("finished"), lacks("checkpoint.npz"), series_covers(0.2))),
    Case("simulate-overwrite-replaces-failed-run", "data_loss",
         (*SIM, *OVR, *OUT), 0, (), (template("failed"),),
         (status("finished"), summary_is(lambda s: s["parameters"]["simulation"]["min_step"] == 0.0,
                                         "the new run's parameters"))),
    Case("simulate-resume-of-finished-run-is-a-no-op", "data_loss",
         (*SIM[:-1], "2", "--resume", *OUT), 0, (), (template("finished"),), (UNCHANGED,),
         note="existing behaviour, kept"),
    Case("simulate-resume-finished-run-other-params-refused", "data_loss",
         (*SIM[:-1], "3", "--resume", *OUT), 2, FOLDER, (template("finished"),), (UNCHANGED,)),
    Case("simulate-resume-other-n-elements-keeps-checkpoint", "data_loss",
         (*KILLED[:3], "5", *KILLED[4:], "--resume", *OUT), 2, ("n_elements",),
         (template("killed"),), (UNCHANGED,)),
    Case("simulate-resume-vtk-has-frames-from-t0", "data_loss",
         (*KILLED, "--vtk", "1", "--resume", *OUT), 0, (), (template("killed_vtk"),),
         (status("finished"), pvd_covers(float(KILLED_T_END), 1.0)),
         note="issue: pvd held only the frames after the resume"),
    Case("simulate-resume-series-from-t0", "data_loss",
         (*KILLED, "--resume", *OUT), 0, (), (template("killed"),),
         (status("finished"), lacks("checkpoint.npz"), series_covers(float(KILLED_T_END)))),
    Case("simulate-resume-interrupted-run-continues", "data_loss",
         (*KILLED, "--resume", *OUT), 0, (), (template("interrupted"),),
         (status("finished"), series_covers(float(KILLED_T_END)))),
    Case("modes-into-modes-result-refused", "data_loss",
         (*MODES[:3], "5", *MODES[4:], *OUT), 2, (*FOLDER, OVERWRITE_FLAG),
         (template("modes"),), (UNCHANGED,)),
    Case("modes-overwrite-replaces-modes-result", "data_loss",
         (*MODES[:3], "5", *MODES[4:], "--plots", *OVR, *OUT), 0, (), (template("modes"),),
         (json_is("modes.json", lambda d: d["parameters"]["rod"]["elements"] == 5,
                  "the new analysis (n_elements 5)"), has("mode_shapes.png"))),
    Case("modes-bad-count-keeps-modes-result", "data_loss",
         (*MODES[:-1], "0", *OUT), 2, ("count",), (template("modes"),), (UNCHANGED,)),
    Case("calibrate-into-calibration-result-refused", "data_loss",
         (*CAL_D, *OUT), 2, (*FOLDER, OVERWRITE_FLAG), (DELTA, template("calibration")),
         (UNCHANGED,)),
    Case("calibrate-overwrite-replaces-calibration-result", "data_loss",
         (*CAL_D, *OVR, *OUT), 0, (), (DELTA, template("calibration")),
         (json_is("calibration.json", lambda d: d["data"].endswith("delta.csv")
                  and d["mode"] == "decrements", "the new calibration"),)),
    Case("calibrate-bad-data-keeps-calibration-result", "data_loss",
         ("calibrate", "--mode", "decrements", "--data", "{tmp}/neg.csv", *OUT), 2,
         ("delta",), (write("neg.csv", "delta\n0.4\n-0.1\n"), template("calibration")),
         (UNCHANGED,)),
    Case("sweep-nan-grid-keeps-existing-study", "data_loss",
         (*SWEEP, *OUT), 2, ("tau",),
         (template("sweep"), study(STUDY_OK.replace("0.04]", "nan]"))), (UNCHANGED,)),
    Case("simulate-refused-while-another-process-holds-lock", "data_loss",
         (*SIM, *OUT), 2, (*FOLDER, "{pid}"), (live_lock,), (UNCHANGED,),
         note="issue: no lock, the last run wins"),
    Case("simulate-overwrite-refused-while-locked", "data_loss",
         (*SIM, *OVR, *OUT), 2, (*FOLDER, "{pid}"), (template("finished"), live_lock),
         (UNCHANGED,)),
    Case("simulate-resume-refused-while-locked", "data_loss",
         (*KILLED, "--resume", *OUT), 2, (*FOLDER, "{pid}"), (template("killed"), live_lock),
         (UNCHANGED,), note="issue: one run deletes the other's checkpoint"),
    Case("modes-refused-while-locked", "data_loss",
         (*MODES, *OUT), 2, (*FOLDER, "{pid}"), (live_lock,), (UNCHANGED,)),
    Case("calibrate-refused-while-locked", "data_loss",
         (*CAL_D, *OUT), 2, (*FOLDER, "{pid}"), (DELTA, live_lock), (UNCHANGED,)),
    Case("sweep-refused-while-locked", "data_loss",
         (*SWEEP, *OUT), 2, (*FOLDER, "{pid}"), (study(STUDY_OK), live_lock), (UNCHANGED,)),
    Case("simulate-takes-over-stale-lock", "data_loss",
         (*SIM, *OUT), 0, (), (stale_lock,), (status("finished"),)),
    Case("modes-takes-over-stale-lock", "data_loss",
         (*MODES, *OUT), 0, (), (stale_lock,), (has("modes.json"),)),
    Case("sweep-takes-over-stale-lock", "data_loss",
         (*SWEEP, *OUT), 0, (), (study(STUDY_OK), stale_lock),
         (csv_has(lambda rows: [r["status"] for r in rows] == ["finished"] * 2,
                  "both points finished"),)),
    Case("simulate-second-process-refused-by-lock", "data_loss",
         (), 2, (*FOLDER, "{pid}"), (), (checkpoint_kept,), mode="custom",
         run=run_second_simulate, slow=True, note="issue: two runs on one folder"),
    Case("simulate-ctrl-c-summary-interrupted-checkpoint-kept", "data_loss",
         (), 130, ("interrupted",), (),
         (status("interrupted"), summary_is(lambda s: s["t_reached"] > 0, "t_reached > 0"),
          checkpoint_kept), mode="custom", run=run_signal_simulate(signal.SIGINT, True),
         slow=True),
    Case("simulate-sigterm-summary-not-running", "data_loss",
         (), (143, 130), (("interrupt", "terminat", "signal", "sigterm"),), (),
         (status("interrupted", "failed"), checkpoint_kept), mode="custom",
         run=run_signal_simulate(signal.SIGTERM, False), slow=True),
    Case("sweep-serial-ctrl-c-keeps-finished-rows", "data_loss",
         (), 130, ("interrupted",), (),
         (csv_has(lambda rows: rows[0]["status"] == "finished"
                  and all(r["status"] != "running" for r in rows),
                  "the first point finished, no point left 'running'"),),
         mode="custom", run=run_sweep_sigint(serial=True), slow=True),

    # ==================================================================================
    # wrong_answer: exit 0 with a result that is wrong, doubtful or silently ambiguous
    # ==================================================================================
    Case("calibrate-record-in-mm", "wrong_answer",
         ("calibrate", "--data", "{tmp}/decay_mm.csv", "--n-elements", "4", *OUT), (1, 2),
         (DATA_NAMED, WHY_UNITS), (data_file("decay_mm.csv", lambda t, x: (t, 1e3 * x)),),
         (calibration_verdict, elapsed_below(HANG_TIMEOUT)), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True, note="issue: tau = 0, CI around 0"),
    Case("calibrate-record-sign-flipped", "wrong_answer",
         ("calibrate", "--data", "{tmp}/decay_flipped.csv", "--n-elements", "4", *OUT), (1, 2),
         (DATA_NAMED, WHY_SIGN), (data_file("decay_flipped.csv", lambda t, x: (t, -x)),),
         (calibration_verdict, elapsed_below(HANG_TIMEOUT)), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True, note="issue: tau 12x too large"),
    Case("calibrate-record-of-pure-noise", "wrong_answer",
         ("calibrate", "--data", "{tmp}/noise.csv", "--n-elements", "4", *OUT), (1, 2),
         (DATA_NAMED, WHY_FIT), (data_file("noise.csv", _noise),),
         (calibration_verdict, elapsed_below(HANG_TIMEOUT)), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True),
    Case("calibrate-model-without-tip-force", "wrong_answer",
         (*CAL_S, "--tip-force", "0", *OUT), (1, 2),
         ((*DATA_NAMED, "tip_force", "tip-force"), WHY_FIT + ("tip", "force", "flat")),
         (lambda ctx: ctx.vars.update(data_name=DATA.name),),
         (calibration_verdict,), mode="subproc", timeout=HANG_TIMEOUT, background=True,
         note="tau = 40 ms with CI [nan, nan], exit 0"),
    Case("calibrate-record-in-metres-is-fine", "wrong_answer",
         (*CAL_S, *OUT), 0, (), (), (tau_near(0.05, 0.1),), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True,
         note="control: the fix must not reject good data"),
    Case("simulate-very-stiff-rod-accurate-or-warned", "wrong_answer",
         (*SIM, "--E", "1e12", "--tau", "1e-6", *OUT), 0, (), (),
         (status("finished"), accurate_or_warned(need_positive_decrements=True)),
         mode="subproc", note="issue: ok with 10 % energy error"),
    Case("simulate-tip-force-0-energy-not-applicable", "wrong_answer",
         (*SIM, "--tip-force", "0", *OUT), 0, (), (), (status("finished"), energy_not_applicable),
         mode="subproc", note="issue: energy error 6.3"),
    Case("simulate-tip-force-1e-12-accurate-or-warned", "wrong_answer",
         (*SIM[:-1], "0.5", "--tip-force", "1e-12", *OUT), 0, (), (),
         (status("finished"), accurate_or_warned()), mode="subproc"),
    Case("simulate-rtol-0.5-warned", "wrong_answer",
         (*SIM[:-1], "0.5", "--rtol", "0.5", *OUT), 0, (), (),
         (status("finished"), accurate_or_warned()), mode="subproc"),
    Case("simulate-rtol-0.01-warned", "wrong_answer",
         (*SIM[:-1], "0.5", "--rtol", "0.01", *OUT), 0, (), (),
         (status("finished"), accurate_or_warned()), mode="subproc"),
    Case("simulate-clean-run-not-warned", "wrong_answer",
         (*SIM, *OUT), 0, (), (), (status("finished"), no_false_warning), mode="subproc",
         note="control: no false alarm"),
    Case("config-tau-then-tau_S-is-ambiguous", "wrong_answer",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("tau", "tau_S"),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\ntau = 0.04\ntau_S = 0.01\n"),),
         (ABSENT,), note="issue: resolved by key order"),
    Case("config-tau_S-then-tau-is-ambiguous", "wrong_answer",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("tau", "tau_S"),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\ntau_S = 0.01\ntau = 0.04\n"),),
         (ABSENT,)),
    Case("config-tau-and-tau_B-is-ambiguous", "wrong_answer",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("tau", "tau_B"),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\ntau_B = 0.0\ntau = 0.04\n"),),
         (ABSENT,)),
    Case("config-top-level-tau-and-table-tau_S-is-ambiguous", "wrong_answer",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("tau", "tau_S"),
         (config("tau = 0.04\n[parameters]\nn_elements = 4\nt_end = 0.2\ntau_S = 0.01\n"),),
         (ABSENT,)),
    Case("study-fixed-tau-grid-tau_S-is-ambiguous", "wrong_answer",
         (*SWEEP, *OUT), 2, ("tau", "tau_S"),
         (study('scenario = "cantilever"\n[fixed]\nn_elements = 4\nt_end = 0.2\ntau = 0.08\n'
                "[grid]\ntau_S = [0.01, 0.02]\n"),), (ABSENT,),
         note="the fixed tau silently drops out: tau_B falls back to its default"),
    Case("study-fixed-tau_B-grid-tau-is-ambiguous", "wrong_answer",
         (*SWEEP, *OUT), 2, ("tau", "tau_B"),
         (study('scenario = "cantilever"\n[fixed]\nn_elements = 4\nt_end = 0.2\ntau_B = 0.0\n'
                "[grid]\ntau = [0.01, 0.02]\n"),), (ABSENT,)),
    Case("static-simply-supported-solves-with-its-spin-gauged", "wrong_answer",
         (*SS, *OUT), 0, (), (),
         (status("finished"),
          summary_is(lambda s: "spin" in s["static"]["gauge"]
                     and s["static"]["largest_displacement"]["node"] == 32
                     and abs(s["static"]["largest_displacement"]["magnitude"] / SS_SAG - 1)
                     < 1e-2, "the spin gauged, the largest displacement at midspan within 1 % "
                     "of 5 q L^4 / (384 E I) + q L^2 / (8 kGA)")),
         note="issue 22: 'load stepping stalled ... singular Jacobian ... limit point'"),
    Case("static-simply-supported-stdout-names-largest-displacement", "wrong_answer",
         (*SS, *OUT), 0, (), (),
         (stdout_has("largest displacement", "node 32"), stdout_lacks("static tip")),
         note="issue 22: 'static tip [0.5, 0, 0]' (the held end)"),
    Case("modes-simply-supported-rigid-spin-n64", "wrong_answer",
         ("modes", "simply_supported", "--count", "3", *OUT), 0, (), (),
         (json_is("modes.json", _ss_modes_ok, "mode 1 rigid (omega 0, zeta null), mode 2 "
                  "bending within 0.5 % of the simply supported Timoshenko beam"),)),
    Case("modes-simply-supported-rigid-spin-n256", "wrong_answer",
         ("modes", "simply_supported", "--n-elements", "256", "--count", "3", *OUT), 0, (),
         (), (json_is("modes.json", _ss_modes_ok, "mode 1 rigid, mode 2 bending within "
                      "0.5 % of the simply supported Timoshenko beam"),),
         note="issue 22: 'internal error: RuntimeError: Factor is exactly singular'"),
    Case("modes-free-free-six-rigid", "wrong_answer",
         ("modes", "simply_supported", "--set", "start.kind=free", "--set", "end.kind=free",
          "--n-elements", "16", "--count", "8", *OUT), 0, (), (),
         (json_is("modes.json", lambda d: [m["family"] for m in d["modes"][:6]]
                  == ["rigid"] * 6 and all(m["omega"] == 0 and m["zeta"] is None
                                          for m in d["modes"][:6])
                  and all(m["family"].startswith("bending") and m["zeta"] is not None
                          for m in d["modes"][6:]), "six rigid modes, then bending"),),
         note="issue 22: rigid modes reported as 'axial' with zeta -0.089, -0.97, inf"),
    Case("modes-n80-count2-not-flaky", "wrong_answer",
         (), 0, (), (), (has("modes.json"),), mode="custom", run=run_modes_repeatedly,
         slow=True, note="issue: 'leading minor not positive definite' one run in three"),
    Case("sweep-failing-point-row-says-failed", "wrong_answer",
         (*SWEEP, *OUT), 1, (("fail",), ("study.csv", "point", "youngs_modulus")),
         (study(STUDY_OK + "[[points]]\ntau = 0.04\nmin_step = 0.19\n"),),
         (csv_has(lambda rows: sorted(r["status"] for r in rows)
                  == ["failed", "finished", "finished"], "2 finished rows and 1 failed row"),)),
    Case("sweep-nan-in-grid-rejected", "wrong_answer",
         (*SWEEP, *OUT), 2, ("tau", "nan"), (study(STUDY_OK.replace("0.04]", "nan]")),),
         (ABSENT,), note="issue: CSV row pending while the point's summary says failed"),
    Case("sweep-nan-youngs-modulus-in-grid-rejected", "wrong_answer",
         (*SWEEP, *OUT), 2, ("youngs_modulus",),
         (study(STUDY_OK + "youngs_modulus = [1e6, nan]\n"),), (ABSENT,)),
    Case("sweep-nan-in-points-rejected", "wrong_answer",
         (*SWEEP, *OUT), 2, ("tau",), (study(STUDY_OK + "[[points]]\ntau = nan\n"),), (ABSENT,)),
    Case("sweep-nan-in-fixed-rejected", "wrong_answer",
         (*SWEEP, *OUT), 2, ("youngs_modulus",),
         (study(STUDY_OK.replace("t_end = 0.2", "t_end = 0.2\nyoungs_modulus = nan")),),
         (ABSENT,)),
    Case("sweep-inf-in-grid-rejected", "wrong_answer",
         (*SWEEP, *OUT), 2, ("tau",), (study(STUDY_OK.replace("0.04]", "inf]")),), (ABSENT,)),

    # ==================================================================================
    # traceback: inputs that end in a Python traceback today
    # ==================================================================================
    Case("simulate-out-is-a-file", "traceback", (*SIM, *OUT), 2, ("afile",),
         (out_is_file,), (UNCHANGED,), **GUARDED),
    Case("modes-out-is-a-file", "traceback", (*MODES, *OUT), 2, ("afile",),
         (out_is_file,), (UNCHANGED,), **GUARDED, note="issue: after the whole computation"),
    Case("calibrate-out-is-a-file", "traceback", (*CAL_D, *OUT), 2, ("afile",),
         (DELTA, out_is_file), (UNCHANGED,), **GUARDED),
    Case("sweep-out-is-a-file", "traceback", (*SWEEP, *OUT), 2, ("afile",),
         (study(STUDY_OK), out_is_file), (UNCHANGED,), **GUARDED),
    Case("compare-damping-out-is-a-file", "traceback",
         ("compare-damping", "--n-elements", "2", *OUT), 2, ("afile",),
         (out_is_file,), (UNCHANGED,), **GUARDED),
    Case("reproduce-out-is-a-file", "traceback",
         ("reproduce", "--n-elements", "4", "--t-end", "0.2", "--skip-derive", "--notes",
          "{tmp}/notes.md", *OUT), 2, ("afile",), (out_is_file,), (UNCHANGED,), **GUARDED),
    Case("notes-beyond-out-is-a-file", "traceback",
         ("notes-beyond", "--out-notes", "{tmp}/beyond.md", *OUT), 2, ("afile",),
         (out_is_file,), (UNCHANGED,), **GUARDED),
    Case("derive-notes-out-below-a-file", "traceback",
         ("derive", "notes", "--out", "{out}/derivation.md"), 2, ("afile",),
         (out_is_file,), (UNCHANGED,)),
    Case("generate-out-is-a-file", "traceback", ("generate", *OUT), 2, ("afile",),
         (out_is_file,), (UNCHANGED,)),
    Case("simulate-out-name-too-long", "traceback", (*SIM, *OUT), 2,
         (("x" * 20, "too long"),), (long_out,), (ABSENT,), **GUARDED),
    Case("modes-out-name-too-long", "traceback", (*MODES, *OUT), 2,
         (("x" * 20, "too long"),), (long_out,), (ABSENT,), **GUARDED),
    Case("calibrate-out-name-too-long", "traceback", (*CAL_D, *OUT), 2,
         (("x" * 20, "too long"),), (DELTA, long_out), (ABSENT,), **GUARDED),
    Case("sweep-out-name-too-long", "traceback", (*SWEEP, *OUT), 2,
         (("x" * 20, "too long"),), (study(STUDY_OK), long_out), (ABSENT,), **GUARDED),
    Case("simulate-out-path-beyond-path-max", "traceback", (*SIM, *OUT), 2,
         (("d" * 20, "too long"),), (deep_out,), (ABSENT,), **GUARDED),
    Case("simulate-out-in-read-only-folder", "traceback", (*SIM, *OUT), 2,
         ("readonly_dir",), (readonly_parent,), (ABSENT,), mode="subproc"),
    Case("modes-out-in-read-only-folder", "traceback", (*MODES, *OUT), 2,
         ("readonly_dir",), (readonly_parent,), (ABSENT,), mode="subproc"),
    Case("calibrate-out-in-read-only-folder", "traceback", (*CAL_D, *OUT), 2,
         ("readonly_dir",), (DELTA, readonly_parent), (ABSENT,), mode="subproc"),
    Case("sweep-out-in-read-only-folder", "traceback", (*SWEEP, *OUT), 2,
         ("readonly_dir",), (study(STUDY_OK), readonly_parent), (ABSENT,), mode="subproc"),
    Case("simulate-resume-truncated-checkpoint", "traceback",
         (*KILLED, "--resume", *OUT), 2, ("checkpoint",),
         (template("killed"), checkpoint_bytes(lambda b: b[: len(b) // 2])), (UNCHANGED,)),
    Case("simulate-resume-checkpoint-missing-arrays", "traceback",
         (*KILLED, "--resume", *OUT), 2, ("checkpoint",),
         (template("killed"), checkpoint_arrays(
             lambda a: {k: v for k, v in a.items() if k not in ("counters_json", "rec_tip")})),
         (UNCHANGED,)),
    Case("simulate-resume-checkpoint-wrong-state-size", "message",
         (*KILLED, "--resume", *OUT), 2, ("checkpoint",),
         (template("killed"), checkpoint_arrays(lambda a: {**a, "y": a["y"][:-7]})),
         (UNCHANGED,)),
    Case("simulate-resume-checkpoint-is-a-folder", "traceback",
         (*KILLED, "--resume", *OUT), 2, ("checkpoint",),
         (template("killed"), checkpoint_is_dir), (UNCHANGED,)),
    Case("config-output_step-1e-12", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("output_step", RANGE),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\noutput_step = 1e-12\n"),),
         (ABSENT,), mode="subproc", as_limit=3 << 30, note="issue: MemoryError"),
    Case("config-atol-1e-300", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("atol", RANGE),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\natol = 1e-300\n"),), (ABSENT,),
         note="issue: ZeroDivisionError"),
    Case("config-length-1e-9", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("length", RANGE),
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\nlength = 1e-9\n"),), (ABSENT,),
         note="issue: IntegrationError traceback"),
    Case("config-density-1e-300", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), (1, 2),
         {1: ("fail",), 2: ("density",)},
         (config("[parameters]\nn_elements = 4\nt_end = 0.2\ndensity = 1e-300\n"),),
         (not_running,)),
    Case("config-scenario-is-a-list", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("scenario",),
         (write("run.toml", 'scenario = ["cantilever"]\n'),), (ABSENT,),
         note="issue: TypeError unhashable"),
    Case("config-scenario-is-a-table", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("scenario",),
         (write("run.toml", 'scenario = {name = "cantilever"}\n'),), (ABSENT,)),
    Case("config-n_elements-1e9", "traceback",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("n_elements", RANGE),
         (config("[parameters]\nt_end = 0.2\nn_elements = 1000000000\n"),), (ABSENT,),
         mode="subproc", as_limit=3 << 30),
    Case("simulate-n-elements-1e9", "traceback",
         (*SIM[:2], "--n-elements", "1000000000", *SIM[4:], *OUT), 2, ("n_elements", RANGE),
         (), (ABSENT,), mode="subproc", as_limit=3 << 30),
    Case("simulate-n-elements-2-pow-31", "traceback",
         (*SIM[:2], "--n-elements", str(2**31), *SIM[4:], *OUT), 2, ("n_elements",),
         (), (ABSENT,), mode="subproc", as_limit=3 << 30),
    Case("modes-n-elements-1e9", "traceback",
         ("modes", "cantilever", "--n-elements", "1000000000", "--count", "2", *OUT), 2,
         ("n_elements",), (), (ABSENT,), mode="subproc", as_limit=3 << 30),
    Case("calibrate-n-elements-1e9", "traceback",
         (*CAL_D[:-1], "1000000000", *OUT), 2, ("n_elements",), (DELTA,), (ABSENT,),
         mode="subproc", as_limit=3 << 30),
    Case("manifest-truncated", "traceback", (*SIM, *OUT), 2, ("MANIFEST.json",),
         (generated_copy(_truncate_manifest),), (ABSENT,), mode="subproc"),
    Case("disk-full-while-writing-summary", "traceback", (*SIM, *OUT), 2, FOLDER, (),
         (not_running,), mode="subproc", fsize_limit=300, note="partial .tmp files left"),
    Case("disk-full-while-writing-series", "traceback", (*SIM, *OUT), 2, FOLDER, (),
         (not_running,), mode="subproc", fsize_limit=2000),
    Case("disk-full-while-writing-plots", "traceback", (*SIM, "--plots", *OUT), 2, FOLDER, (),
         (not_running,), mode="subproc", fsize_limit=8000),
    Case("disk-full-while-writing-modes", "traceback", (*MODES, *OUT), 2, FOLDER, (),
         (), mode="subproc", fsize_limit=1000),
    Case("disk-full-while-writing-calibration", "traceback", (*CAL_D, *OUT), 2, FOLDER,
         (DELTA,), (), mode="subproc", fsize_limit=200),
    Case("disk-full-while-writing-study", "traceback", (*SWEEP, *OUT), 2,
         ((OUT_NAME, "space", "too large", "disk", "write"),),
         (study(STUDY_OK),), (), mode="subproc", fsize_limit=1000),
    Case("sweep-ctrl-c-dask-no-worker-tracebacks", "traceback",
         (), 130, ("interrupted",), (),
         (csv_has(lambda rows: all(r["status"] != "running" for r in rows),
                  "no point left 'running'"),),
         mode="custom", run=run_sweep_sigint(serial=False), slow=True,
         note="issue: worker tracebacks / log lines after Ctrl-C"),
    Case("sweep-two-on-one-folder", "traceback",
         (), 2, (*FOLDER, "{pid}"), (), (), mode="custom", run=run_two_sweeps, slow=True,
         note="issue: two sweeps on one folder"),

    # ==================================================================================
    # message: a failure whose one stderr line is missing, misplaced or does not name
    # the culprit
    # ==================================================================================
    Case("simulate-garbage-checkpoint-named", "message",
         (*KILLED, "--resume", *OUT), 2, ("checkpoint.npz",),
         (template("killed"), checkpoint_bytes(lambda b: b"garbage\n")), (UNCHANGED,)),
    Case("simulate-t-end-1e300-named", "message",
         (*SIM[:-1], "1e300", *OUT), 2, ("t_end", RANGE), (), (ABSENT,)),
    Case("config-t_end-1e300-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("t_end", RANGE),
         (config("[parameters]\nn_elements = 4\nt_end = 1e300\n"),), (ABSENT,)),
    Case("simulate-t-end-1e-300", "message",
         (*SIM[:-1], "1e-300", *OUT), (1, 2), {1: ("fail",), 2: ("t_end",)}, (),
         (not_running,)),
    Case("simulate-solver-failure-on-stderr", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 1, ("fail",),
         (config("[parameters]\nn_elements = 4\nt_end = 1.0\nmin_step = 0.2\n"),),
         (status("failed"), has("summary.json", "series.npz")),
         note="today the failure line goes to stdout"),
    Case("simulate-static-failure-on-stderr", "message",
         (*SIM, "--tip-force", "1e6", *OUT), 1, (("fail",), ("static", "equilibrium")), (),
         (status("failed"), has("summary.json"))),
    Case("simulate-E-1e-300", "message",
         (*SIM, "--E", "1e-300", *OUT), (1, 2), {1: ("fail",), 2: ("youngs_modulus",)}, (),
         (not_running,)),
    Case("static-free-free-under-gravity-refused", "message",
         (*SS, "--set", "start.kind=free", "--set", "end.kind=free", *OUT), 2,
         ("free-free", "net force", "start.kind"), (), (ABSENT,),
         note="issue 22: 'singular Jacobian ... may have a limit point'"),
    Case("static-E-1e-300-says-double-precision", "message",
         (*SS, "--E", "1e-300", *OUT), 2, ("youngs_modulus", "double precision"), (),
         (ABSENT,), note="issue 22: 'singular Jacobian ... may have a limit point'"),
    Case("static-horizontal-pendulum-refused", "message",
         ("static", "pendulum", *OUT), 2, ("pinned start", 'start.kind = "clamped"'), (),
         (ABSENT,)),
    Case("static-sideways-sag-gauge-reacts-fails", "message",
         (*SS, "--set", "section.height=0.02", "--set", "rod.geometry.normal=[0,0.6,0.8]",
          *OUT), 1, ("fail", "gauge", "start.kind"), (),
         (status("failed"), has("summary.json", "static.npz"))),
    Case("calibrate-binary-data-file-named", "message",
         ("calibrate", "--data", "{tmp}/garbage.csv", *OUT), 2, ("garbage.csv",),
         (write("garbage.csv", bytes(range(256)) * 8),), (ABSENT,)),
    Case("calibrate-utf16-data-file-named", "message",
         ("calibrate", "--data", "{tmp}/utf16.csv", *OUT), 2, ("utf16.csv",),
         (write("utf16.csv", "t,x\n0,0.2\n0.1,0.1\n".encode("utf-16")),), (ABSENT,)),
    Case("calibrate-flat-signal-names-data", "message",
         ("calibrate", "--data", "{tmp}/flat.csv", *OUT), 2, (("flat.csv", "--data"),),
         (write("flat.csv", "t,x\n" + "".join(f"{i / 10},0.0\n" for i in range(40))),),
         (ABSENT,)),
    Case("calibrate-tau0-negative-named", "message",
         (*CAL_D, "--tau0", "-1", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,)),
    Case("calibrate-tau0-zero-named", "message",
         (*CAL_D, "--tau0", "0", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,)),
    Case("calibrate-tau0-nan-named", "message",
         (*CAL_D, "--tau0", "nan", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,)),
    Case("calibrate-tau0-inf-named", "message",
         (*CAL_D, "--tau0", "inf", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,)),
    Case("calibrate-tip-force-nan-named", "message",
         (*CAL_D, "--tip-force", "nan", *OUT), 2, ("tip_force", RANGE), (DELTA,), (ABSENT,)),
    Case("config-utf16-file-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("run.toml",),
         (write("run.toml", 'scenario = "cantilever"\n'.encode("utf-16")),), (ABSENT,)),
    Case("study-utf16-file-named", "message",
         (*SWEEP, *OUT), 2, ("study.toml",), (write("study.toml", STUDY_OK.encode("utf-16")),),
         (ABSENT,)),
    Case("config-youngs_modulus-inf-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("youngs_modulus", "range"),
         (config("[parameters]\nn_elements = 4\nyoungs_modulus = inf\n"),), (ABSENT,)),
    Case("config-rtol-nan-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("rtol", "range"),
         (config("[parameters]\nn_elements = 4\nrtol = nan\n"),), (ABSENT,)),
    Case("config-max_order-float-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("max_order",),
         (config("[parameters]\nn_elements = 4\nmax_order = 2.0\n"),), (ABSENT,)),
    Case("config-atol-negative-named", "message",
         ("simulate", "--config", "{tmp}/run.toml", *OUT), 2, ("atol", "range"),
         (config("[parameters]\nn_elements = 4\natol = -1e-9\n"),), (ABSENT,)),
    Case("study-n_elements-string-named", "message",
         (*SWEEP, *OUT), 2, ("n_elements",),
         (study(STUDY_OK + 'n_elements = [4, "many"]\n'),), (ABSENT,)),
    Case("manifest-missing", "message", (*SIM, *OUT), 2, ("MANIFEST.json",),
         (generated_copy(_remove_manifest),), (ABSENT,), mode="subproc",
         note="issue: an edited kernel is compiled without a word"),
    Case("kernel-edited-without-manifest", "message", (*SIM, *OUT), 2,
         (("MANIFEST.json", "rod_kernels.c"),),
         (generated_copy(lambda g: (_remove_manifest(g), _edit_kernel(g))),), (ABSENT,),
         mode="subproc"),
    Case("kernel-edited-against-manifest", "message", (*SIM, *OUT), 2, ("rod_kernels.c",),
         (generated_copy(_edit_kernel),), (ABSENT,), mode="subproc",
         note="passes today but only after write_status"),

    # ==================================================================================
    # hang: inputs that run for minutes (or forever) instead of being refused
    # ==================================================================================
    Case("calibrate-record-in-ms", "hang",
         ("calibrate", "--data", "{tmp}/decay_ms.csv", "--n-elements", "4", *OUT), (1, 2),
         (DATA_NAMED, WHY_SPAN), (data_file("decay_ms.csv", lambda t, x: (1e3 * t, x)),),
         (calibration_verdict, elapsed_below(HANG_TIMEOUT)), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True, note="issue: runs for minutes"),
    Case("sweep-grid-far-above-limit-refused", "hang",
         (*SWEEP, *OUT), 2, (CONFIRM_FLAG, ("point", "grid")),
         (study('scenario = "cantilever"\n[fixed]\nt_end = 0.2\n[grid]\ntau = ['
                + ", ".join(f"{0.001 * (i + 1):.4g}" for i in range(101)) + "]\nn_elements = ["
                + ", ".join(str(i + 2) for i in range(1000)) + "]\n"),),
         (ABSENT,), mode="subproc", timeout=20, slow=True, background=True,
         note="issue: a 10^6-point grid is accepted (and the table is O(n^2) per write)"),
    Case("sweep-confirm-flag-accepted", "hang",
         (*SWEEP, CONFIRM_FLAG, *OUT), 0, (), (study(STUDY_OK),),
         (csv_has(lambda rows: len(rows) == 2, "2 rows"),)),
    Case("sweep-1200-failing-points-in-linear-time", "hang",
         (*SWEEP, *OUT), (1, 2), {1: ("fail",), 2: ("youngs_modulus",)},
         (study('scenario = "cantilever"\n[fixed]\nn_elements = 4\nt_end = 0.2\n[grid]\n'
                "youngs_modulus = [" + ", ".join(f"-{i + 1}.0" for i in range(1200)) + "]\n"),),
         (elapsed_below(15),), mode="subproc", timeout=15, slow=True, background=True,
         note="issue: study.csv rewritten twice per point"),
    Case("simulate-vtk-every-nanosecond-refused", "hang",
         (*SIM, "--vtk", "1e-9", *OUT), 2, ("vtk",), (), (ABSENT,), mode="subproc",
         as_limit=3 << 29, timeout=HANG_TIMEOUT, slow=True, background=True),

    # ==================================================================================
    # issue 22: the hostile review (problem files, sections, ends, Maxwell, DMA, plots,
    # sweeps, calibrate, compare-damping)
    # ==================================================================================
    Case("constitutive-edited-against-manifest", "wrong_answer", (*SIM, *OUT), 2,
         ("constitutive.py", "kvrod generate"), (generated_copy(_edit_constitutive),),
         (ABSENT,), mode="subproc", note="issue 22: tau_E x 1.5 ran without a word"),
    Case("points-csv-letter-O-named", "wrong_answer",
         ("static", "{tmp}/rod.toml", *OUT), 2, ("pts.csv", "line 3", "column 2"),
         (write("pts.csv", "x,y,z\n0,0,0\n0.05,O,0.15\n0,0,0.3\n"),
          points_problem(file="pts.csv")), (ABSENT,), **GUARDED,
         note="issue 22: the row was dropped and the rod came out straight"),
    Case("points-csv-four-columns-named", "wrong_answer",
         ("static", "{tmp}/rod.toml", *OUT), 2, ("pts.csv", "line 2"),
         (write("pts.csv", "0,0,0\n0.05,0,0.15,0.2\n0,0,0.3\n"),
          points_problem(file="pts.csv")), (ABSENT,), **GUARDED,
         note="a fourth column was cut off without a word"),
    Case("points-fold-back-named", "message",
         ("static", "{tmp}/rod.toml", *OUT), 2, ("rod.geometry.points", "row 2"),
         (points_problem("[[0,0,0],[0,0,0.1],[0,0,0.2],[0,0,0.1],[0,0,0.3]]"),), (ABSENT,),
         **GUARDED, note="issue 22: named as rod.geometry.function = <function ...>"),
    Case("calibrate-n-elements-0-refused", "wrong_answer",
         (*CAL_D[:-1], "0", *OUT), 2, ("n_elements", RANGE), (DELTA,), (ABSENT,), **GUARDED,
         note="issue 22: silently used 16"),
    Case("compare-damping-tip-force-0-refused", "wrong_answer",
         ("compare-damping", "--n-elements", "4", "--tip-force", "0", *OUT), 2,
         ("tip_force", RANGE), (), (ABSENT,), **GUARDED, note="issue 22: NaN ratios"),
    Case("compare-damping-tip-force-1e-300-refused", "wrong_answer",
         ("compare-damping", "--n-elements", "4", "--tip-force", "1e-300", *OUT), 2,
         ("tip_force", RANGE), (), (ABSENT,), **GUARDED),
    Case("compare-damping-tau-S-1e-300-refused", "wrong_answer",
         ("compare-damping", "--n-elements", "4", "--tau-S", "1e-300", *OUT), 2,
         ("tau_S", RANGE), (), (ABSENT,), **GUARDED, note="issue 22: a 300-digit ratio"),
    Case("compare-damping-tau-S-1e-3-refused", "wrong_answer",
         ("compare-damping", "--n-elements", "4", "--tau-S", "1e-3", *OUT), 2,
         ("tau_S", RANGE), (), (ABSENT,), **GUARDED,
         note="found: measured ratio 0.11 for a predicted 1.3 (undamped higher modes)"),
    Case("compare-damping-no-consistent-damping-refused", "wrong_answer",
         ("compare-damping", "--n-elements", "4", "--tau-S", "0", "--tau-B", "0.04", "--nu",
          "0.5", *OUT), 2, ("tau_B", RANGE), (), (ABSENT,), **GUARDED,
         note="found: tau_E = 0 on the consistent route, a ratio of noise"),
    Case("simulate-resume-maxwell-continues", "data_loss",
         (*MAXWELL_KILLED, "--resume", *OUT), 0, (), (template("killed_maxwell"),),
         (status("finished"), lacks("checkpoint.npz"), series_covers(2000.0)),
         slow=True, note="issue 22: 'checkpoint holds a state y of shape (201,)'"),
    Case("simulate-tau-1e300-named", "traceback",
         (*SIM, "--tau", "1e300", *OUT), 2, ("tau", RANGE), (), (ABSENT,), **GUARDED,
         note="issue 22: internal error (consistent_initial)"),
    Case("simulate-tau-S-1e300-named", "traceback",
         (*SIM, "--tau-S", "1e300", *OUT), 2, ("tau_S", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-tau-B-1e300-named", "traceback",
         (*SIM, "--tau-B", "1e300", *OUT), 2, ("tau_B", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-tau-1e9-at-n4-named", "traceback",
         (*SIM, "--tau", "1e9", *OUT), 2, ("tau", RANGE), (), (ABSENT,), **GUARDED,
         note="the bound follows the stiffest element mode, not only overflow"),
    Case("simulate-tau-1e6-at-n4-runs", "traceback",
         (*SIM, "--tau", "1e6", *OUT), 0, (), (), (status("finished"),),
         note="control: an overdamped rod within the bound runs"),
    Case("compare-damping-tau-B-1e300-named", "traceback",
         ("compare-damping", "--n-elements", "4", "--tau-B", "1e300", *OUT), 2,
         ("tau_B", RANGE), (), (ABSENT,), **GUARDED),
    Case("calibrate-tip-force-1e300-named", "traceback",
         (*CAL_S, "--tip-force", "1e300", *OUT), 2, ("tip_force", RANGE), (), (ABSENT,),
         **GUARDED, note="issue 22: internal error (StaticSolveError)"),
    Case("compare-damping-tip-force-1e300-named", "traceback",
         ("compare-damping", "--n-elements", "4", "--tip-force", "1e300", *OUT), 2,
         ("tip_force", RANGE), (), (ABSENT,), **GUARDED),
    Case("plot-truncated-series-named", "traceback",
         ("plot", "{out}"), 2, ("series.npz", "damaged"),
         (template("finished"), series_bytes(lambda b: b[: len(b) // 2])), (UNCHANGED,),
         note="issue 22: internal error BadZipFile"),
    Case("plot-series-of-other-shape-named", "traceback",
         ("plot", "{out}"), 2, ("series.npz", "damaged"),
         (template("finished"), series_bytes(lambda b: _reshaped_series(b))), (UNCHANGED,)),
    Case("modes-tau-1e300-named", "message",
         (*MODES, "--tau", "1e300", *OUT), 2, ("tau", RANGE), (), (ABSENT,), **GUARDED,
         note="issue 22: 'array must not contain infs or NaNs'"),
    Case("calibrate-tau0-1e300-named", "message",
         (*CAL_D, "--tau0", "1e300", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,),
         **GUARDED, note="issue 22: 'array must not contain infs or NaNs'"),
    Case("calibrate-tau0-1e-300-named", "message",
         (*CAL_D, "--tau0", "1e-300", *OUT), 2, ("tau0", RANGE), (DELTA,), (ABSENT,),
         **GUARDED, note="issue 22: 'Initial guess is outside of provided bounds'"),
    Case("simulate-tip-force-1e300-one-line", "message",
         (*SIM, "--tip-force", "1e300", *OUT), 2, ("tip_force", RANGE), (), (ABSENT,),
         **GUARDED, note="issue 22: a dozen RuntimeWarning lines before exit 1"),
    Case("static-load-1e300-named", "message",
         ("static", "cantilever", "--n-elements", "4", "--set", "loads.0.vector=[1e300,0,0]",
          *OUT), 2, ("loads.0.vector", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-gravity-1e300-named", "message",
         (*SIM, "--set", 'loads.1={{kind="gravity", vector=[0,0,1e300]}}', *OUT), 2,
         ("loads.1.vector", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-harmonic-amplitude-1e300-named", "message",
         (*SIM, "--set", 'loads.0.time={{kind="harmonic", amplitude=1e300, frequency=1}}',
          *OUT), 2, ("loads.0.time", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-t-end-1e-300-refused", "message",
         (*SIM[:-1], "1e-300", *OUT), 2, ("t_end", RANGE), (), (ABSENT,), **GUARDED,
         note="issue 22: accepted, then 'step size 1e-303'"),
    Case("calibrate-dma-nan-plain-number", "message",
         ("calibrate", "--dma", "{tmp}/dma.csv", "--nu", "0.3", *OUT), 2,
         ("dma.csv", "line 4", "storage"),
         (write("dma.csv", "# a DMA test\nfrequency_hz,storage,loss\n0.1,1e6,1e5\n"
                "1,nan,2e5\n10,3e6,1e5\n"),), (ABSENT, no_text("np.float64")),
         note="issue 22: np.float64(nan) in the message"),
    Case("calibrate-dma-text-cell-named", "message",
         ("calibrate", "--dma", "{tmp}/dma.csv", "--nu", "0.3", *OUT), 2,
         ("dma.csv", "line 3", "'abc'"),
         (write("dma.csv", "frequency_hz,storage,loss\n0.1,1e6,1e5\n1,abc,2e5\n"
                "10,3e6,1e5\n"),), (ABSENT, no_text("np.float64", "nan")),
         note="a text cell was reported as nan"),
    Case("calibrate-dma-600-decades-refused", "message",
         ("calibrate", "--dma", "{tmp}/dma.csv", "--nu", "0.3", *OUT), 2,
         ("dma.csv", "decades"),
         (write("dma.csv", "frequency_hz,storage,loss\n1e-300,1e6,1e5\n1,2e6,1e5\n"
                "1e300,3e6,1e5\n"),), (ABSENT,)),
    Case("calibrate-dma-huge-moduli-one-line", "message",
         ("calibrate", "--dma", "{tmp}/dma.csv", "--nu", "0.3", *OUT), (1, 2),
         {1: ("fit rejected",), 2: ("dma.csv",)},
         (write("dma.csv", "frequency_hz,storage,loss\n1,1e300,1e5\n2,2e300,1\n"
                "3,1e308,1e5\n"),), (),
         note="found: matplotlib's overflow RuntimeWarning before the line"),
    Case("calibrate-heavy-noise-still-fits", "wrong_answer",
         ("calibrate", "--data", "{tmp}/noisy.csv", "--n-elements", "4", *OUT), 0, (),
         (data_file("noisy.csv", _noisy(0.03)),), (tau_near(0.05, 0.1),), mode="subproc",
         timeout=HANG_TIMEOUT, slow=True, background=True,
         note="issue 22: refused as 'check the units of t' (period from noise maxima)"),
    Case("set-appends-a-load", "message",
         (*SIM, "--set", 'loads.1={{kind="force", vector=[0,0,0.001], at="end"}}', *OUT), 0,
         (), (), (status("finished"), summary_loads(2)),
         note="issue 22: refused ('an index 0 ... 0')"),
    Case("set-appends-a-maxwell-branch", "message",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.branches.3={{tau=0.5, youngs_modulus=1e5, poisson_ratio=0.3}}", *OUT), 0,
         (), (), (status("finished"), summary_is(
             lambda s: len(s["parameters"]["material"]["branches"]) == 4, "4 branches"))),
    Case("set-index-beyond-append-named", "message",
         (*SIM, "--set", 'loads.2={{kind="force", vector=[0,0,1]}}', *OUT), 2,
         ("loads.2", "0 ... 1"), (), (ABSENT,), **GUARDED),
    Case("set-sub-key-of-missing-entry-says-append", "message",
         (*SIM, "--set", "loads.1.vector=[0,0,1]", *OUT), 2, ("loads.1", "append"), (),
         (ABSENT,), **GUARDED),
    Case("set-whole-material-table", "message",
         (*SIM, "--set", "material={{youngs_modulus=2e6, tau=0.01}}", *OUT), 0, (), (),
         (status("finished"), summary_is(
             lambda s: s["parameters"]["material"]["youngs_modulus"] == 2e6, "E = 2e6"))),
    Case("set-load-position-s-replaces-at", "message",
         (*SIM, "--set", "loads.0.s=0.15", *OUT), 0, (), (),
         (status("finished"), summary_is(
             lambda s: s["parameters"]["loads"][0].get("s") == 0.15
             and "at" not in s["parameters"]["loads"][0], "the load at s = 0.15 m")),
         note="found: refused, 'not together with at' (the resolved problem holds at)"),
    Case("set-material-eta-replaces-tau", "message",
         (*SIM, "--set", "material.eta=1000.0", *OUT), 0, (), (),
         (status("finished"), summary_is(
             lambda s: abs(s["parameters"]["material"]["tau_S"] - 0.0026) < 1e-12
             and s["parameters"]["material"]["tau_B"] == 0.04, "tau_S = eta/G, tau_B kept")),
         note="found: refused, 'not together with tau_S'"),
    Case("set-maxwell-branch-youngs-modulus", "message",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.branches.0.youngs_modulus=1e7", *OUT), 0, (), (), (status("finished"),),
         note="found: refused, 'shear_modulus not together with youngs_modulus'"),
    Case("simulate-origin-1e300-named", "wrong_answer",
         (*SIM, "--set", "rod.geometry.origin=[1e300,0,0]", *OUT), 2,
         ("rod.geometry.origin", RANGE), (), (ABSENT,), **GUARDED,
         note="found: a failed static solve blamed on a 'limit point'"),
    Case("simulate-clamp-translation-1e300-named", "wrong_answer",
         (*SIM, "--set", "start.motion={{translation=[1e300,0,0]}}", *OUT), 2,
         ("start.motion.translation", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-clamp-angle-1e300-named", "wrong_answer",
         (*SIM, "--set", "start.motion={{rotation_angle=1e300}}", *OUT), 2,
         ("start.motion.rotation_angle", RANGE), (), (ABSENT,), **GUARDED),
    Case("simulate-section-width-1e300-named", "traceback",
         (*SIM, "--set", "section.width=1e300", *OUT), 2, ("section.width", RANGE), (),
         (ABSENT,), **GUARDED, note="found: internal error OverflowError"),
    Case("simulate-section-width-1e-300-named", "message",
         (*SIM, "--set", "section.width=1e-300", *OUT), 2, ("section.width", RANGE), (),
         (ABSENT,), **GUARDED, note="found: named as parameter 'I2' = 0.0"),
    Case("simulate-rod-length-1e300-named", "traceback",
         (*SIM, "--set", "rod.length=1e300", *OUT), 2, ("rod.length", RANGE), (),
         (ABSENT,), **GUARDED, note="found: internal error OverflowError"),
    Case("simulate-harmonic-1e300-hz-refused", "hang",
         (*SIM, "--set", 'loads.0.time={{kind="harmonic", frequency=1e300}}', *OUT), 2,
         ("frequency", RANGE), (), (ABSENT,), **GUARDED,
         note="found: ran for minutes (killed at 120 s)"),
    Case("simulate-maxwell-branch-tau-1e-300-named", "traceback",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.branches.0.tau=1e-300", *OUT), 2, ("material.branches", "tau", RANGE),
         (), (ABSENT,), **GUARDED, note="found: internal error (consistent_initial)"),
    Case("simulate-maxwell-branch-1e300-pa-named", "message",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.branches.0.youngs_modulus=1e300", *OUT), 2,
         ("material.branches.0", "glassy"), (), (ABSENT,), **GUARDED,
         note="found: a failed static solve blamed on a 'limit point'"),
    Case("simulate-maxwell-fluid-static-start-named", "message",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.youngs_modulus=0", *OUT), 2, ("simulation.initial", "reference"), (),
         (ABSENT,), **GUARDED,
         note="found: named as parameter 'E' = 0.0, though documented as allowed"),
    Case("simulate-maxwell-fluid-from-reference-runs", "message",
         ("simulate", "maxwell_cantilever", "--n-elements", "4", "--t-end", "0.1", "--set",
          "material.youngs_modulus=0", "--set", 'simulation.initial="reference"', *OUT), 0,
         (), (), (status("finished"),)),
    Case("simulate-name-with-dotdot-stays-in-results", "data_loss",
         ("simulate", "{tmp}/rod.toml"), 0, (), (write("rod.toml", 'name = "../../escaped"\n'
          '[rod]\nlength = 0.3\nelements = 4\n[section]\nkind = "circle"\nradius = 0.005\n'
          '[simulation]\nt_end = 0.05\n'),),
         (lambda ctx, r: None if (ctx.tmp / "results").is_dir()
          and not (ctx.tmp.parent / "escaped").exists()
          else "results written outside results/ (the problem's name held '../..')",),
         mode="subproc", note="found: wrote results/../../escaped"),
    Case("calibrate-maxwell-problem-named", "message",
         (*CAL_D, "--problem", "maxwell_cantilever", *OUT), 2,
         ("maxwell_cantilever", "--dma"), (DELTA,), (ABSENT,), **GUARDED,
         note="found: 'tau (material.tau) ... a known key'"),
    Case("compare-damping-nu-names-nu", "message",
         ("compare-damping", "--n-elements", "4", "--nu", "-0.99", *OUT), 2, ("nu", RANGE),
         (), (ABSENT,), **GUARDED, note="found: blamed tau_S"),
    Case("sweep-appends-a-load-per-point", "message",
         (*SWEEP, *OUT), 0, (),
         (study('scenario = "cantilever"\n[fixed]\nn_elements = 4\nt_end = 0.2\n[grid]\n'
                '"loads.1" = [{kind = "force", vector = [0, 0, 0.001]}]\n'),),
         (csv_has(lambda rows: [r["status"] for r in rows] == ["finished"], "1 finished"),),
         note="found: a table value was 'the wrong type'"),
    Case("calibrate-record-typo-named-by-line", "message",
         ("calibrate", "--data", "{tmp}/typo.csv", "--n-elements", "4", *OUT), 2,
         ("typo.csv", "line 3", "'O.12'"),
         (write("typo.csv", "t,x\n0,0.2\n0.01,O.12\n0.02,0.19\n"),), (ABSENT,), **GUARDED,
         note="found: 'x contains NaN or inf (first at row 1)': the data row, not the line"),
    Case("calibrate-record-gap-named-by-line", "message",
         ("calibrate", "--data", "{tmp}/gap.csv", "--n-elements", "4", *OUT), 2,
         ("gap.csv", "line 3", "empty"),
         (write("gap.csv", "t,x\n0,0.2\n0.01,\n0.02,0.19\n"),), (ABSENT,), **GUARDED),
    # ==================================================================================
    # kvrod section: composite sections of named materials (issue 25)
    # ==================================================================================
    Case("section-writes-json-and-png", "data_loss", (*SEC, *OUT), 0, (), (section_file(),),
         (has("section.json", "section.png"),
          json_is("section.json", lambda d: len(d["stiffness"]) == 6
                  and d["reference_point"] == d["elastic_centroid"]
                  and d["mesh"]["converged"], "a converged 6x6 result")),
         ),
    Case("section-bad-poisson-ratio-named", "message", (*SEC, *OUT), 2,
         ("materials.sheath.poisson_ratio", RANGE),
         (section_file("poisson_ratio = 0.45", "poisson_ratio = 0.7"),), (ABSENT,),
         **GUARDED),
    Case("section-overlapping-regions-named", "message", (*SEC, *OUT), 2,
         ("section.regions[1]", "overlap", "section.regions[0]"),
         (section_file("inner_radius = 0.001", "inner_radius = 0.0005"),), (ABSENT,),
         **GUARDED),
    Case("section-unknown-material-name-named", "message", (*SEC, *OUT), 2,
         ("section.regions[1].material", "sheeth"),
         (section_file('material = "sheath"', 'material = "sheeth"'),), (ABSENT,),
         **GUARDED),
    Case("section-non-spd-stiffness-named", "message", (*SEC, *OUT), 2,
         ("materials.sheath.stiffness_matrix", "positive definite", "Pa"),
         (section_file(*SPD_BAD),), (ABSENT,), **GUARDED),
    Case("section-maxwell-region-refused", "message", (*SEC, *OUT), 2,
         ("materials.sheath.model", "maxwell"),
         (section_file("tau_S = 0.01", 'tau_S = 0.01\nmodel = "generalized_maxwell"'),),
         (ABSENT,), **GUARDED),
    Case("section-material-beside-composite-named", "message", (*SEC, *OUT), 2,
         ("material", "composite"),
         (section_file('name = "two_layers"', 'name = "two_layers"\n[material]\ntau = 0.1'),),
         (ABSENT,), **GUARDED),
    Case("section-into-finished-section-refused", "data_loss", (*SEC, *OUT), 2,
         (*FOLDER, OVERWRITE_FLAG), (section_file(), template("section")), (UNCHANGED,),
         **GUARDED),
    Case("section-bad-file-keeps-finished-section", "data_loss", (*SEC, *OVR, *OUT), 2,
         ("materials.sheath.density",),
         (section_file("density = 1200.0", "density = -1.0"), template("section")),
         (UNCHANGED,), **GUARDED),
    Case("section-overwrite-replaces-section", "data_loss", (*SEC, "--set",
                                                             "materials.sheath.tau_S=0.02",
                                                             *OVR, *OUT), 0, (),
         (section_file(), template("section")),
         (json_is("section.json", lambda d: d["materials"]["sheath"]["tau_S"] == 0.02,
                  "the new analysis (tau_S = 0.02)"),)),
    # zones and given section matrices (issue 26): the hostile review of helper-13
    Case("static-set-zones-0-appends-the-first-zone", "message",
         ("static", "cantilever", "--n-elements", "4", "--set",
          "zones.0={{from=0.0, to=0.15, material={{youngs_modulus=2e6}}}}", *OUT), 0, (), (),
         (summary_is(lambda s: len(s["parameters"]["zones"]) == 1, "one zone"),),
         note="was refused: 'zones' = {'0': ...} is not an array of tables"),
    Case("static-zone-shorter-than-a-node-named", "wrong_answer",
         ("static", "cantilever", "--n-elements", "4", "--set",
          "zones=[{{from=0.0, to=1e-12, material={{youngs_modulus=2e6}}}}]", *OUT), 2,
         ("zones[0]", "longer than"), (), (ABSENT,),
         note="a zone between two nodes changed nothing, silently (issue 26); since issue "
              "30 nodes go at every zone boundary, so only a zone shorter than their "
              "tolerance has no segment of its own"),
    Case("modes-tau-beside-a-viscosity-matrix-named", "wrong_answer",
         ("modes", "coupled_strip", "--n-elements", "4", "--count", "2", "--tau", "0.1",
          *OUT), 2, ("material.tau", "section.viscosity_matrix"), (), (ABSENT,),
         note="taken, reported as tau_E = 0.1 s, acting nowhere"),
    # composite sections run since issue 26 (tests/runtime/section/test_problem_composite.py);
    # a generalized Maxwell region is refused, naming its material
    Case("simulate-composite-maxwell-region-refused", "message",
         ("simulate", "{tmp}/rod.toml", *OUT), 2, ("materials.sheath.model", "kelvin_voigt"),
         (write("rod.toml", '[rod]\nlength = 0.3\nelements = 4\n' + MAXWELL_REGION),),
         (ABSENT,), **GUARDED),
    Case("static-composite-maxwell-region-refused", "message",
         ("static", "{tmp}/rod.toml", *OUT), 2, ("materials.sheath.model", "kelvin_voigt"),
         (write("rod.toml", '[rod]\nlength = 0.3\nelements = 4\n' + MAXWELL_REGION),),
         (ABSENT,), **GUARDED),
    # ==================================================================================
    # issue 30: the hostile run of the new inputs
    # ==================================================================================
    Case("section-decimal-plies-in-seconds", "hang", ("section", "{tmp}/plies.toml", *OUT),
         0, (), (write("plies.toml", PLIES),),
         (json_is("section.json", lambda d: d["mesh"]["converged"]
                  and d["mesh"]["nodes"] < 20000, "a converged section of a small mesh"),
          elapsed_below(HANG_TIMEOUT)), mode="subproc", timeout=HANG_TIMEOUT,
         as_limit=4 << 30, background=True,
         note="hung: the mesher refined an 8.7e-19 m sliver, 60 MB/s until killed"),
    Case("modes-of-decimal-plies-rod", "hang", ("modes", "{tmp}/rod.toml", "--count", "2",
                                                *OUT), 0, (),
         (write("rod.toml", PLIES_ROD),), (has("modes.json"), elapsed_below(HANG_TIMEOUT)),
         mode="subproc", timeout=HANG_TIMEOUT, as_limit=4 << 30, background=True),
    Case("section-ctrl-c-inside-the-analysis", "hang", (), 130, ("interrupted",),
         (write("plies.toml", PLIES),), (elapsed_below(10.0), ABSENT), mode="custom",
         run=run_signal_section(signal.SIGINT, ["section", "{tmp}/plies.toml", "--tol",
                                                "1e-9", *OUT]),
         note="Triangle and SuperLU hold the main thread: Ctrl-C waited for them (the "
              "round-off plies: forever)"),
    Case("section-sigterm-inside-the-analysis", "hang", (), (143, 130),
         (("terminated", "interrupted"),), (write("plies.toml", PLIES),),
         (elapsed_below(10.0), ABSENT), mode="custom", run=run_signal_section(
             signal.SIGTERM, ["section", "{tmp}/plies.toml", "--tol", "1e-9", *OUT])),
    Case("calibrate-ctrl-c-in-a-simulation-is-interrupted", "traceback", (), 130,
         ("interrupted",), (), (ABSENT,), mode="custom",
         run=run_signal_calibrate(signal.SIGINT), slow=True,
         note="internal error: RuntimeError (simulation ... failed: interrupted)"),
    Case("plot-damaged-static-named", "traceback", ("plot", "{out}"), 2,
         ("static.npz", "damaged"),
         (template("static"), npz_bytes("static.npz", lambda b: b[: len(b) // 2])),
         (UNCHANGED,), note="internal error BadZipFile"),
    Case("plot-damaged-modes-npz-named", "traceback", ("plot", "{out}"), 2, ("modes.npz",),
         (template("modes"), npz_bytes("modes.npz", lambda b: b[: len(b) // 3])),
         (UNCHANGED,), note="internal error BadZipFile (a held-out variant of the static)"),
    Case("simulate-E-1e300-names-E", "message", (*SIM, "--E", "1e300", *OUT), 2,
         ("youngs_modulus", RANGE), (), (ABSENT,), **GUARDED,
         note="named simulation.t_end, after the periods E gave"),
    Case("modes-density-1e-300-names-density", "message",
         (*MODES, "--set", "material.density=1e-300", *OUT), 2, ("material.density", RANGE),
         (), (ABSENT,), **GUARDED),
    Case("section-material-E-1e300-named", "message", (*SEC, *OUT), 2,
         ("materials.core.youngs_modulus", RANGE),
         (section_file("youngs_modulus = 1e11", "youngs_modulus = 1e300"),), (ABSENT,),
         **GUARDED, note="analysed, not converged, exit 0"),
    Case("calibrate-negative-tip-force-named", "message",
         (*CAL_S, "--tip-force", "-0.05", *OUT), 2, ("--tip-force", "negative"), (),
         (ABSENT,), note="blamed the record: 'is the sign of the record flipped?'"),
    Case("calibrate-record-100-s-late-named", "wrong_answer",
         ("calibrate", "--data", "{tmp}/late.csv", "--n-elements", "4", *OUT), 2,
         (DATA_NAMED, ("offset", "since the release")),
         (data_file("late.csv", lambda t, x: (t + 100.0, x)),), (ABSENT,),
         note="fitted, exit 0, a wrong tau"),
    Case("calibrate-record-0.37-s-late-named", "wrong_answer",
         ("calibrate", "--data", "{tmp}/late.csv", "--n-elements", "4", *OUT), 2,
         (DATA_NAMED, "offset"), (data_file("late.csv", lambda t, x: (t + 0.37, x)),),
         (ABSENT,), note="fit rejected for its residual, the offset unnamed"),
    Case("calibrate-record-with-a-still-start-named", "wrong_answer",
         ("calibrate", "--data", "{tmp}/still.csv", "--n-elements", "4", *OUT), 2,
         (DATA_NAMED, "before the release"), (data_file("still.csv", _still_start),),
         (ABSENT,)),
    Case("modes-draws-pngs-only-with-plots", "message", (*MODES, *OUT), 0, (), (),
         (has("modes.json", "modes.npz"), lacks("mode_shapes.png", "mode_shapes_3d.png")),
         note="drew both PNGs every time (simulate draws only with --plots)"),
    Case("modes-plots-draws-pngs", "message", (*MODES, "--plots", *OUT), 0, (), (),
         (has("modes.json", "mode_shapes.png", "mode_shapes_3d.png"),)),
    Case("simulate-into-section-folder-refused", "data_loss", (*SIM, *OUT), 2,
         (*FOLDER, "section.json", OVERWRITE_FLAG), (template("section"),), (UNCHANGED,),
         note="the run was written beside the section result"),
    Case("section-into-run-folder-refused", "data_loss", (*SEC, *OUT), 2,
         (*FOLDER, "summary.json", OVERWRITE_FLAG), (section_file(), template("finished")),
         (UNCHANGED,), **GUARDED),
    Case("modes-into-section-folder-refused", "data_loss", (*MODES, *OUT), 2,
         (*FOLDER, "section.json"), (template("section"),), (UNCHANGED,)),
    # ==================================================================================
    # obstacles and the contact law (issue 32): each refusal is one line naming the key
    # and the allowed range, before anything is computed or written
    # ==================================================================================
    *(Case(f"contact-{cid}-named", "message",
           ("static", "cantilever", "--n-elements", "4", *sets, *OUT), 2, needles, (),
           (ABSENT,), **GUARDED) for cid, sets, needles in (
        ("zero-normal", ("--set", CONTACT_R, "--set",
                         'obstacles.0={{kind="plane", point=[0,0,-1], normal=[0,0,0]}}'),
         ("obstacles[0].normal", "not all zero")),
        ("nan-axis", ("--set", CONTACT_R, "--set",
                      'obstacles.0={{kind="cylinder", point=[1,0,0], axis=[nan,0,1], '
                      'radius=0.1}}'), ("obstacles[0].axis", "finite")),
        ("negative-radius", ("--set", CONTACT_R, "--set",
                             'obstacles.0={{kind="sphere", centre=[1,0,0], radius=-0.1}}'),
         ("obstacles[0].radius", "> 0")),
        ("negative-friction", ("--set", CONTACT_R, "--set", FLOOR, "--set",
                               "obstacles.0.friction=-0.3"),
         ("obstacles[0].friction", "0 ... 100")),
        ("unknown-kind", ("--set", CONTACT_R, "--set",
                          'obstacles.0={{kind="cube", point=[1,0,0]}}'),
         ("obstacles[0].kind", "'plane', 'sphere', 'cylinder'")),
        ("inside-on-a-plane", ("--set", CONTACT_R, "--set", FLOOR, "--set",
                               "obstacles.0.inside=true"),
         ("obstacles[0].inside", "only for kind = 'cylinder'")),
        ("length-on-a-sphere", ("--set", CONTACT_R, "--set",
                                'obstacles.0={{kind="sphere", centre=[1,0,0], radius=0.1, '
                                'length=0.2}}'),
         ("obstacles[0].length", "only for kind = 'cylinder'")),
        ("radius-missing-for-a-rectangle", ("--set", FLOOR),
         ("contact.radius", "required for a rectangle section")),
        ("restitution-above-one", ("--set", CONTACT_R, "--set", FLOOR, "--set",
                                   "contact.restitution=1.5"),
         ("contact.restitution", "(0, 1]")),
        ("rod-starting-inside", ("--set", CONTACT_R, "--set",
                                 'obstacles.0={{kind="plane", point=[0,0,0.1], '
                                 'normal=[0,0,1]}}'),
         ("obstacles[0]", "node at s = 0 m", "0.105 m inside")),
        ("table-that-changes-nothing", ("--set", "contact={{restitution=0.5}}"),
         ("contact", "changes nothing")),
    )),
    Case("contact-assembly-rod-starting-inside-named", "message",
         ("static", "assembly_two_rod_cantilever", "--n-elements", "4", "--set", CONTACT_R,
          "--set", 'obstacles.0={{kind="sphere", centre=[0,0,0.25], radius=0.01}}', *OUT),
         2, ("obstacles[0]", "[rod tip]", "inside"), (), (ABSENT,), **GUARDED),
]

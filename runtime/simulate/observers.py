"""Observers of the run loop: they watch accepted steps on the integrator's dense output.

An observer implements any of

* ``begin(run)``: the run starts (``run.t``, ``run.y``, ``run.yp`` hold the initial values);
* ``step(run, dense, t0, t1)``: a step ``[t0, t1]`` was accepted; ``dense(t)`` and
  ``dense.derivative(t)`` interpolate y and y' on it, ``dense.values(ts)`` both at once
  (rows per time);
* ``end(run)``: the run stopped (finished, failed or interrupted);
* ``state() -> dict`` / ``restore(dict)``: what a checkpoint must keep to continue.

They are called in the order given, so an observer may use the results of earlier ones
(:class:`Sampler` reads the running integrals of :class:`EnergyIntegrator`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from runtime.solvers.roots import bracketed_root

#: Gauss-Legendre nodes/weights on [0, 1] for the per-step energy quadrature
GL_X = (np.polynomial.legendre.leggauss(3)[0] + 1.0) / 2.0
GL_W = np.polynomial.legendre.leggauss(3)[1] / 2.0


class Observer(Protocol):
    """What the run loop calls (every method optional; see the module docstring)."""

    name: str


class EnergyModel(Protocol):
    """The part of a model the energy observers need."""

    def energy_scalars(self, t: float, y: np.ndarray, yp: np.ndarray | None = None
                       ) -> tuple[float, ...]:
        """(T, W, 2D, P_ext[, P_bc]) of a state: J, J, W, W[, W]."""
        ...

    def energies(self, ts: np.ndarray, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
        """The same for m states at once: (m, 5)."""
        ...


class EnergyIntegrator:
    """Running integrals of the dissipated power 2D and the external power P over the run.

    Each accepted step is integrated on its interpolant by 3-point Gauss-Legendre (one
    kernel call for the three nodes). ``partial(dense, t0, t1, t)`` gives the integrals
    from the step's start to a ``t`` inside it (for outputs) from the same three values:
    the integral of their quadratic interpolant, which equals the Gauss-Legendre sum at
    ``t = t1`` (so outputs and the running totals agree at step ends) and is accurate to
    O(h^3) of the step inside it. ``dissipated`` and ``external_work`` hold the integrals
    up to the last accepted step (J). The external power includes the power of prescribed
    end motion when the model reports it (a fifth scalar).
    """

    name = "energy"
    #: maps the values at the Gauss nodes to the coefficients of their quadratic in
    #: x = (t - t0) / h: (c0, c1, c2) = _FIT @ values
    _FIT = np.linalg.inv(np.vander(GL_X, 3, increasing=True))

    def __init__(self, model: EnergyModel) -> None:
        self.model = model
        self.dissipated = 0.0
        self.external_work = 0.0
        self._key: tuple[float, float] | None = None
        self._coef = np.zeros((3, 2))

    def _step_values(self, dense, t0: float, t1: float) -> np.ndarray:
        """Coefficients (3, 2) of 2D and P as quadratics in x on the step [t0, t1]."""
        if self._key != (t0, t1):
            tq = t0 + (t1 - t0) * GL_X
            ys, yps = dense.values(tq)                # (3, n) each: one interpolation
            e = self.model.energies(tq, ys, yps)      # one kernel call for the 3 nodes
            power = e[:, 3] + (e[:, 4] if e.shape[1] > 4 else 0.0)
            self._coef = self._FIT @ np.column_stack([e[:, 2], power])
            self._key = (t0, t1)
        return self._coef

    def partial(self, dense, t0: float, t1: float, t: float) -> tuple[float, float]:
        """(int 2D dt, int P dt) over [t0, t] inside the accepted step [t0, t1]."""
        h = t1 - t0
        if h == 0.0 or t == t0:
            return 0.0, 0.0
        c = self._step_values(dense, t0, t1)
        x = (t - t0) / h
        d, w = (c[0] * x + c[1] * x * x / 2.0 + c[2] * x ** 3 / 3.0) * h
        return float(d), float(w)

    def step(self, run: Run, dense, t0: float, t1: float) -> None:
        d, w = self.partial(dense, t0, t1, t1)
        self.dissipated += d
        self.external_work += w

    def state(self) -> dict[str, Any]:
        return {"diss": self.dissipated, "work": self.external_work}

    def restore(self, st: dict[str, Any]) -> None:
        self.dissipated, self.external_work = float(st["diss"]), float(st["work"])


class Sampler:
    """Samples on a uniform output grid: end points, energies and their running integrals.

    Records per output time ``t``: ``tip`` (3,) the position of node N (the s = L end),
    ``start`` (3,) of node 0, kinetic ``T`` and elastic ``W`` energy (J), dissipated
    energy ``int 2D`` and external work ``int P`` (J) since the start.
    """

    name = "sampler"

    def __init__(self, model, energy: EnergyIntegrator, t_out: np.ndarray,
                 tip_index: np.ndarray, start_index: np.ndarray) -> None:
        self.model, self.energy = model, energy
        self.t_out = np.asarray(t_out, dtype=float)
        self.i_tip, self.i_start = np.asarray(tip_index), np.asarray(start_index)
        self.k_out = 0
        self.rec: dict[str, list] = {"t": [], "tip": [], "start": [], "T": [], "W": [],
                                     "D": [], "P": []}

    def _record(self, tq: float, y: np.ndarray, T: float, W: float, diss: float,
                work: float) -> None:
        r = self.rec
        r["t"].append(tq)
        r["tip"].append(y[self.i_tip].copy())
        r["start"].append(y[self.i_start].copy())
        r["T"].append(T)
        r["W"].append(W)
        r["D"].append(diss)
        r["P"].append(work)

    def begin(self, run: Run) -> None:
        if self.k_out == 0 and self.t_out.size and self.t_out[0] <= run.t:
            e = self.model.energy_scalars(run.t, run.y, run.yp)
            self._record(run.t, run.y, e[0], e[1], 0.0, 0.0)
            self.k_out = 1

    def step(self, run: Run, dense, t0: float, t1: float) -> None:
        # called before the energy integrator adds this step: its totals end at t0
        k0, k = self.k_out, self.k_out
        slack = 1e-12 * max(1.0, abs(t1))
        while k < self.t_out.size and self.t_out[k] <= t1 + slack:
            k += 1
        if k == k0:
            return
        ts = np.minimum(self.t_out[k0:k], t1)
        ys, yps = dense.values(ts)                        # all outputs of the step at once
        en = self.model.energies(ts, ys, yps)             # one kernel call
        e = self.energy
        for j, tq in enumerate(ts):
            dd, ww = e.partial(dense, t0, t1, float(tq))
            self._record(float(tq), ys[j], float(en[j, 0]), float(en[j, 1]),
                         e.dissipated + dd, e.external_work + ww)
        self.k_out = k

    def arrays(self) -> dict[str, np.ndarray]:
        r = self.rec
        return {"t": np.array(r["t"]),
                "tip": np.array(r["tip"]).T if r["tip"] else np.zeros((3, 0)),
                "start": np.array(r["start"]).T if r["start"] else np.zeros((3, 0)),
                "kinetic": np.array(r["T"]), "elastic": np.array(r["W"]),
                "dissipated": np.array(r["D"]), "external_work": np.array(r["P"])}

    def state(self) -> dict[str, Any]:
        a = self.arrays()
        return {"k_out": self.k_out, "rec_t": a["t"], "rec_tip": a["tip"].T,
                "rec_start": a["start"].T, "rec_T": a["kinetic"], "rec_W": a["elastic"],
                "rec_D": a["dissipated"], "rec_P": a["external_work"]}

    def restore(self, st: dict[str, Any]) -> None:
        self.k_out = int(st["k_out"])
        r = self.rec
        for key, src in (("t", "rec_t"), ("T", "rec_T"), ("W", "rec_W"), ("D", "rec_D"),
                         ("P", "rec_P")):
            r[key] = [float(v) for v in st[src]]
        r["tip"] = [np.array(v) for v in st["rec_tip"]]
        start = st.get("rec_start")
        r["start"] = ([np.array(v) for v in start] if start is not None and len(start)
                      else [np.full(3, math.nan) for _ in r["t"]])


class Maxima:
    """Maxima of one state component (e.g. the tip's x), located on the dense output.

    A maximum is where the matching velocity component crosses zero downwards; its time is
    refined by Brent's method on the step's interpolant. Values are reported relative to
    ``offset`` (the component's reference value: a displacement). ``positive_only`` keeps maxima
    with a positive value (the decay of a vibration about zero); ``initial`` also counts a
    release from rest at a positive value as a maximum at the start time.
    """

    name = "maxima"

    def __init__(self, position_index: int, velocity_index: int, *,
                 positive_only: bool = True, initial: bool = True,
                 offset: float = 0.0) -> None:
        self.ix, self.iv = int(position_index), int(velocity_index)
        self.offset = float(offset)     # reported values are y[ix] - offset
        self.positive_only, self.initial = positive_only, initial
        self.t: list[float] = []
        self.x: list[float] = []
        self._v_old = 0.0

    def _keep(self, x: float) -> bool:
        return x > 0 or not self.positive_only

    def begin(self, run: Run) -> None:
        self._v_old = float(run.y[self.iv])
        x0 = float(run.y[self.ix]) - self.offset
        if self.initial and not self.t and x0 > 0 and self._keep(x0):
            self.t.append(run.t)
            self.x.append(x0)

    def step(self, run: Run, dense, t0: float, t1: float) -> None:
        v_new = float(run.y[self.iv])
        if self._v_old > 0.0 >= v_new and t1 > t0:
            tk = t1 if v_new == 0.0 else bracketed_root(
                lambda s: float(dense(s)[self.iv]), t0, t1, self._v_old, v_new,
                xtol=1e-14)
            xk = float(dense(tk)[self.ix]) - self.offset
            if self._keep(xk):
                self.t.append(tk)
                self.x.append(xk)
        self._v_old = v_new

    def state(self) -> dict[str, Any]:
        return {"peaks_t": np.array(self.t), "peaks_x": np.array(self.x)}

    def restore(self, st: dict[str, Any]) -> None:
        self.t = [float(v) for v in st["peaks_t"]]
        self.x = [float(v) for v in st["peaks_x"]]


class Snapshots:
    """Full states every ``every`` seconds (for VTK), handed to ``sink(t, y)`` at once."""

    name = "snapshots"

    def __init__(self, every: float, sink: Callable[[float, np.ndarray], object]) -> None:
        self.every, self.sink = float(every), sink
        self.next = math.nan

    def begin(self, run: Run) -> None:
        if not math.isfinite(self.next):
            self.sink(run.t, run.y.copy())
            self.next = run.t + self.every

    def step(self, run: Run, dense, t0: float, t1: float) -> None:
        while self.next <= t1:
            self.sink(self.next, np.array(dense(self.next)))
            self.next += self.every

    def state(self) -> dict[str, Any]:
        return {"snap_next": self.next}

    def restore(self, st: dict[str, Any]) -> None:
        self.next = float(st.get("snap_next", math.nan))


class Progress:
    """Calls ``callback(t)`` after every accepted step (a progress bar)."""

    name = "progress"

    def __init__(self, callback: Callable[[float], object]) -> None:
        self.callback = callback

    def step(self, run: Run, dense, t0: float, t1: float) -> None:
        self.callback(t1)


class Run(Protocol):
    """The loop's view of a run in progress (see :class:`runtime.simulate.loop.RunState`)."""

    t: float
    y: np.ndarray
    yp: np.ndarray

"""Rod problems and models for the tests (built through the public problem schema)."""

from __future__ import annotations

from typing import Any

import numpy as np

from runtime.model.quaternion import quat_exp, quat_mul
from runtime.model.rod import RodModel
from runtime.problem.assemble import build_model
from runtime.problem.schema import Problem

#: dead loads on every test rod with loads=True: force at the end, moment at the end,
#: gravity (not along any axis, so no component vanishes by symmetry)
DEAD_LOADS = [
    {"kind": "force", "at": "end", "vector": [0.05, -0.02, 0.01]},
    {"kind": "moment", "at": "end", "vector": [0.001, 0.002, -0.003]},
    {"kind": "gravity", "vector": [0.0, -9.81, 1.0]},
]


def rod_mapping(N: int = 6, start: str = "clamped", end: str = "free", tau: float = 0.04,
                loads: bool | list = True, geometry: dict | None = None,
                section: dict | None = None, **material: Any) -> dict:
    """A problem table: the paper's material, a 10 x 12 mm rectangle, L = 0.3 m."""
    mat = {"density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3, "tau": tau}
    mat.update(material)
    if tau is None or "tau_S" in material or "tau_B" in material:
        mat.pop("tau")
    return {
        "name": "test",
        "rod": {"elements": N, **({"geometry": geometry} if geometry else {}),
                **({} if geometry and geometry.get("kind", "straight") != "straight"
                   else {"length": 0.3})},
        "section": section or {"kind": "rectangle", "width": 0.01, "height": 0.012},
        "material": mat,
        "start": {"kind": start}, "end": {"kind": end},
        "loads": (DEAD_LOADS if loads is True else (loads or [])),
    }


def rod_problem(*args, **kw) -> Problem:
    return Problem.from_mapping(rod_mapping(*args, **kw))


def rod_model(*args, backend: str = "auto", **kw) -> RodModel:
    return build_model(rod_problem(*args, **kw), backend=backend)


def random_state(m: RodModel, rng, amp: float = 0.2, unit: bool = False) -> np.ndarray:
    """A perturbed reference: moved nodes, rotated (and, unless unit, scaled) quaternions,
    random velocities; held nodes at their prescribed position and velocity."""
    y = m.reference.copy()
    y[m.phi_index[1:]] += 0.01 * rng.standard_normal(m.phi_index[1:].shape)
    p = quat_mul(y[m.p_index], quat_exp(amp * rng.standard_normal((m.N, 3))))
    if not unit:
        p *= rng.uniform(0.7, 1.4, (m.N, 1))
    y[m.p_index] = p
    y[m.v_index] = rng.standard_normal(m.v_index.shape)
    y[m.omega_index] = 3 * rng.standard_normal(m.omega_index.shape)
    return m.constrain(y)


def residual(m: RodModel, y: np.ndarray, yp: np.ndarray, t: float = 0.0) -> np.ndarray:
    r = np.empty(m.n)
    m.residual(t, y, yp, r)
    return r


def central_difference_jacobian(f, y: np.ndarray, rel: float = 1e-6) -> np.ndarray:
    """The columns (f(y + h e_k) - f(y - h e_k)) / (2 h), h = rel max(1, |y_k|): the
    Jacobian of f (a state's residual) by central differences."""
    cols = []
    for k in range(y.size):
        h = rel * max(1.0, abs(y[k]))
        e = np.zeros(y.size)
        e[k] = h
        cols.append((f(y + e) - f(y - e)) / (2 * h))
    return np.stack(cols, axis=1)


#: a generalized Maxwell material for rod_mapping(..., tau=None, **MAXWELL): two branches
#: with their own Poisson ratios (so extension gets 2 extra relaxation times: B = 4)
MAXWELL: dict[str, Any] = {
    "model": "generalized_maxwell",
    "branches": [{"youngs_modulus": 2e6, "poisson_ratio": 0.45, "tau": 0.01},
                 {"shear_modulus": 3e5, "bulk_modulus": 1e6, "tau": 0.2}],
}


def with_internal_strains(m: RodModel, y: np.ndarray, rng, amp: float = 1e-2) -> np.ndarray:
    """y with random internal strains of the relaxation terms (a copy)."""
    y = np.array(y, dtype=float)
    y[m.q_segment_index] = amp * rng.standard_normal(m.q_segment_index.shape)
    y[m.q_joint_index] = 10 * amp * rng.standard_normal(m.q_joint_index.shape)
    return y


def energy_rate_function(m: RodModel):
    """CasADi function ``dE(y, d, par)``: the directional derivative of T + W (kinetic plus
    stored energy) along the state direction ``d``, with the clamp frames turning with
    ``Omega_start``/``Omega_end`` (``p' = 1/2 p*(0, Omega)`` enters dW/dt too)."""
    import casadi as ca

    from generated import rod_layout as L
    from runtime.model.casadi_oracle import CasadiOracle

    cr = CasadiOracle(m.arrays)
    ys, ds = ca.MX.sym("y", m.n), ca.MX.sym("d", m.n)
    ps = ca.MX.sym("par", m.arrays.par.size)
    out = cr.energies(0.0, ys, ds, ps, *CasadiOracle.args(m.arrays)[1:])
    dpar = np.zeros(m.arrays.par.size)
    for name in ("start", "end"):
        k = L.PARAM_OFFSETS["p_" + name]
        p = m.arrays.param("p_" + name)
        dpar[k:k + 4] = 0.5 * quat_mul(p, np.r_[0.0, m.arrays.param("Omega_" + name)])
    return ca.Function("dE", [ys, ds, ps], [ca.jtimes(out[0] + out[1], ca.vertcat(ys, ps),
                                                       ca.vertcat(ds, ca.DM(dpar)))])


def move_held_ends(m: RodModel, seed: int = 11) -> RodModel:
    """Hand-set end motion for kernel tests: random velocities and accelerations of held
    ends, random angular velocities and turned frames of clamped ends; the drive is
    removed so that nothing overwrites them. Returns ``m``."""
    a = m.arrays
    rng = np.random.default_rng(seed)
    for name in ("start", "end"):
        if a.held(name):
            a.set_param("v_" + name, rng.standard_normal(3))
            a.set_param("a_" + name, rng.standard_normal(3))
        if a.clamped(name):
            a.set_param("Omega_" + name, rng.standard_normal(3))
            p = quat_mul(a.param("p_" + name), quat_exp(0.3 * rng.standard_normal(3)))
            a.set_param("p_" + name, p)
    m.drive = None
    return m

"""Reference values for the example problems in ``examples/*.toml``.

Each function takes the parsed TOML document of an example (a plain dict: the numbers a
user wrote, not kvrod's interpretation of them) and returns what the other reference
modules predict for it. Section constants come from :mod:`.sections` (textbook
formulas), never from kvrod's generated code. SI units unless the example says otherwise.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import bend45, clamped, helix, pendulum, rollup, sections, supported
from . import viscoelastic_beam as vb

Doc = dict[str, Any]


def _shear_modulus(mat: Doc) -> float:
    return mat["youngs_modulus"] / (2.0 * (1.0 + mat["poisson_ratio"]))


def rollup_reference(doc: Doc) -> dict[str, Any]:
    """Roll-up by the end moment about d2 = e2 (rolls toward +x): ``EI`` (E I2), the
    closing moment, and ``tip(f)``: the end position (x, y, z) at load factor ``f``."""
    s, m = doc["section"], doc["material"]
    sec = sections.rectangle(s["width"], s["height"], m["poisson_ratio"])
    EI = m["youngs_modulus"] * sec.I2
    L = doc["rod"]["length"]
    M = doc["loads"][0]["vector"][1]

    def tip(f: float) -> np.ndarray:
        u, w, _ = rollup.rollup_tip(f * M, EI, L)
        return np.array([u, 0.0, w])

    def curve(f: float, s_: np.ndarray) -> np.ndarray:
        u, w, _ = rollup.rollup_curve(s_, f * M, EI)
        return np.vstack([u, np.zeros_like(u), w])

    return {"L": L, "EI": EI, "M": M, "closing_moment": rollup.closing_moment(EI, L),
            "tip": tip, "curve": curve}


def bend45_reference(doc: Doc) -> dict[str, Any]:
    """The 45-degree bend: the prescribed stiffnesses and ``tip(P)`` (converged)."""
    return {"stiffness": bend45.bend45_stiffness(), "P": doc["loads"][0]["vector"][2],
            "tip": bend45.bend45_tip}


def helix_reference(doc: Doc) -> dict[str, float]:
    """Axial compliance (m/N) of the spring loaded on its axis: with extension and shear
    of the wire (``full``) and the classical pitch-corrected formula (``classical``); the
    coil radius and the load ``F``."""
    g, m = doc["rod"]["geometry"], doc["material"]
    sec = sections.circle(doc["section"]["radius"], m["poisson_ratio"])
    E, G = m["youngs_modulus"], _shear_modulus(m)
    args = (g["coil_radius"], g["pitch"], g["turns"])
    full = helix.spring_compliance_axis(*args, EI=E * sec.I1, GJ=G * sec.J_T, EA=E * sec.A,
                                        GA=G * sec.kappa_1 * sec.A)
    classical = helix.spring_compliance_classical(*args, EI=E * sec.I1, GJ=G * sec.J_T)
    return {"full": full, "classical": classical, "R": g["coil_radius"],
            "F": doc["loads"][0]["vector"][2], "wire_length": helix.wire_length(*args)}


def clamped_both_reference(doc: Doc) -> dict[str, Any]:
    """Sag under gravity along -e3 (bending about d1, E I1; shear along d2, kappa_2):
    ``w(x)`` (downward, m) and the midspan value."""
    m, s = doc["material"], doc["section"]
    sec = sections.rectangle(s["width"], s["height"], m["poisson_ratio"])
    E, G = m["youngs_modulus"], _shear_modulus(m)
    q = m["density"] * sec.A * abs(doc["loads"][0]["vector"][2])
    L = doc["rod"]["length"]
    kw = {"L": L, "EI": E * sec.I1, "kGA": G * sec.kappa_2 * sec.A}
    return {"q": q, "L": L, "midspan": clamped.clamped_uniform_load_deflection(q, **kw),
            "shear_part": q * L * L / (8.0 * kw["kGA"]),
            "curve": lambda x: clamped.clamped_uniform_load_curve(x, q, **kw)}


def simply_supported_reference(doc: Doc) -> dict[str, Any]:
    """Sag under gravity along -e3 (bending about d1, E I1; shear along d2, kappa_2):
    ``w(x)`` (downward, m), the midspan value, and the first bending frequencies of both
    planes (rad/s) of the simply supported Timoshenko beam."""
    m, s = doc["material"], doc["section"]
    sec = sections.rectangle(s["width"], s["height"], m["poisson_ratio"])
    E, G = m["youngs_modulus"], _shear_modulus(m)
    rho = m["density"]
    q = rho * sec.A * abs(doc["loads"][0]["vector"][2])
    L = doc["rod"]["length"]
    kw = {"L": L, "EI": E * sec.I1, "kGA": G * sec.kappa_2 * sec.A}
    freq = {f"bending-{i}": supported.simply_supported_timoshenko_frequencies(
        3, L=L, rho=rho, A=sec.A, E=E, I=I, kGA=G * kappa * sec.A)
        for i, I, kappa in ((1, sec.I1, sec.kappa_2), (2, sec.I2, sec.kappa_1))}
    return {"q": q, "L": L,
            "midspan": supported.simply_supported_uniform_load_deflection(q, **kw),
            "shear_part": q * L * L / (8.0 * kw["kGA"]),
            "curve": lambda x: supported.simply_supported_uniform_load_curve(x, q, **kw),
            "frequencies": freq}


def pendulum_reference(doc: Doc) -> dict[str, Any]:
    """The rigid compound pendulum of the same rod released from horizontal: period and
    ``angle(t)`` from the downward vertical."""
    r, L, rho = doc["section"]["radius"], doc["rod"]["length"], doc["material"]["density"]
    A = math.pi * r * r
    mass = rho * A * L
    g = abs(doc["loads"][0]["vector"][2])
    # rotary inertia of the sections about the pin-parallel axis: I / A = r^2 / 4
    kw = {"I_O": pendulum.rod_pivot_inertia(mass, L, r * r / 4.0), "m": mass, "g": g,
          "d": L / 2}
    return {"period": pendulum.period(**kw), "angle": lambda t: pendulum.angle(t, **kw),
            "energy": mass * g * L / 2}


def base_excitation_reference(doc: Doc) -> dict[str, float]:
    """Steady tip amplitude ``X |T(omega)|`` (m) of the complex-modulus Timoshenko
    cantilever (and the Euler-Bernoulli one) at the drive frequency of the example."""
    m, s = doc["material"], doc["section"]
    mo = doc["start"]["motion"]
    X = float(np.linalg.norm(mo["translation"]))
    omega = 2.0 * math.pi * mo["translation_time"]["frequency"]
    sec = sections.rectangle(s["width"], s["height"], m["poisson_ratio"])
    E, G = vb.kelvin_voigt_moduli(m["youngs_modulus"], m["poisson_ratio"], m["tau"], m["tau"])
    geo = {"L": doc["rod"]["length"], "rho": m["density"], "A": sec.A, "I": sec.I2}
    T = vb.timoshenko_transmissibility(omega, kappa=sec.kappa_1, E=E, G=G, **geo)[0]
    Te = vb.euler_bernoulli_transmissibility(omega, E=E, **geo)[0]
    return {"X": X, "omega": omega, "T": abs(T), "amplitude": X * abs(T),
            "amplitude_euler_bernoulli": X * abs(Te), "phase": float(np.angle(T))}

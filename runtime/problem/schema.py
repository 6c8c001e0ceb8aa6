"""The problem description: one schema for the Python API and for TOML files.

A :class:`Problem` is a frozen tree of dataclasses::

    name, description
    rod         Rod(geometry, elements)             [rod], [rod.geometry]
    section     Shape | GivenStiffness | Composite  [section] (+ [materials.NAME])
    material    KelvinVoigt | GeneralizedMaxwell    [material] (None: composite section)
    start, end  End(kind, motion)                   [start], [end]
    loads       tuple[Load, ...]                    [[loads]]
    simulation  Simulation(t_end, rtol, atol, ...)  [simulation]
    statics     Statics(load_steps, report)         [statics]
    analysis    Analysis(maxima)                    [analysis]
    zones       tuple[Zone, ...]                    [[zones]]
    points      tuple[float, ...]                   (an assembly's named points on the rod)

:meth:`Problem.from_mapping` builds it from a TOML table (every value checked, every
error naming its key, value and allowed range), :meth:`Problem.to_mapping` writes it back
(the resolved problem in a results folder), :meth:`Problem.with_overrides` applies
``{"material.tau": 0.02, "rod.elements": 30}`` (dotted paths, or the short
:data:`ALIASES` of the command line and of sweeps) through the same checks. The problem
file reference lists every key: ``kvrod problem-keys`` (:mod:`runtime.problem.keys`).
A file of several rods (``[rods.NAME]`` tables, joints, bodies) is an
:class:`~runtime.problem.assembly.Assembly` of such problems.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.geometry import (
    NODE_SNAP_RTOL,
    Curve,
    Geometry,
    Straight,
    geometry_from_mapping,
    node_arc_lengths,
)
from runtime.problem.loads import End, Load, end_from_mapping, load_from_mapping
from runtime.problem.materials import (
    GeneralizedMaxwell,
    Material,
    material_from_mapping,
)
from runtime.problem.sections import (
    DAMPING_ROUTES,
    Composite,
    GivenStiffness,
    Section,
    section_from_mapping,
)

#: guards against runs that cannot finish on one machine
MAX_ELEMENTS = 200_000          # ~1 GiB of band storage and work arrays
MAX_SAMPLES = 10_000_000        # output samples t_end / output_step
MAX_PERIODS = 1e6               # first-mode periods in t_end (~50 steps each)
MAX_FRAMES = 10_000             # centreline frames of a run
#: what the BDF error test may control (Simulation.error_control)
ERROR_CONTROLS = ("auto", "state", "configuration")
MAX_FRAME_VALUES = 7e7          # frames x nodes x 3 (~0.5 GiB of stored positions)
#: smallest accepted tolerances (below them the error test works on round-off)
RTOL_MIN = 100 * float(np.finfo(float).eps)
ATOL_MIN = 1e-20
#: fastest viscous rate tau omega_max^2 (1/s) of a discrete Kelvin-Voigt rod accepted:
#: 0.1/eps. The integrator forms its iteration matrices (and the consistent initial
#: accelerations) from the viscous and inertial terms together; where the viscous rate
#: of the stiffest element mode exceeds 1/eps times the inertia, the inertia is lost to
#: round-off (measured: cantilever N = 4 / 50 / 400 fails from tau = 1e9 / 1e8 / 1e6 s,
#: rates 4e16 / 4e15 / 2e15 1/s; this bound keeps a 10 % margin below the first failure).
VISCOUS_RATE_MAX = 0.1 / float(np.finfo(float).eps)
#: largest load accepted, as the strain (or, for a moment, the rotation in rad) it would
#: cause if the rod's softest stiffness carried it alone: ``|F| / min(EA, GA)``,
#: ``|q| L / min(EA, GA)``, ``rho A |g| L / min(EA, GA)``, ``|M| L / min(EI, GJ)``. A
#: linear rod law means nothing long before a strain of 1; the bound only keeps out loads
#: whose solve cannot mean anything (1e300 N overflows the residual) while a merely too
#: large load (1e6 N on the paper's cantilever, a strain of 3e4) still runs and fails with
#: its own message.
LOAD_STRAIN_MAX = 1e6
#: below this Young's modulus (Pa; the softest real solids, gels, have 10 ... 100 Pa) a
#: load beyond LOAD_STRAIN_MAX or a t_end below the fastest mode's round-off scale is
#: blamed on the material, by the statics' own check (runtime.model.rigid)
SOFT_E_MIN = 1.0
_LOAD_UNITS = {"force": "N", "distributed": "N/m", "gravity": "m/s^2", "moment": "N m"}
#: largest ratio of a generalized Maxwell solid's glassy to equilibrium shear or bulk modulus
#: (real polymers: 1e2 ... 1e4; at 1e300 the static solve meets a singular Jacobian)
GLASSY_RATIO_MAX = 1e10
#: first root of 1 + cos(x) cosh(x) = 0 (clamped-free Euler-Bernoulli beam)
BETA1_L = 1.8751040687119611

TOP_KEYS = ("name", "description", "rod", "section", "material", "materials", "start", "end",
            "loads", "simulation", "statics", "analysis", "zones")


@dataclass(frozen=True)
class Rod:
    """The rod's reference geometry and its number of elements."""

    geometry: Geometry = field(default_factory=lambda: Straight(rod_length=0.3))
    elements: int = 50

    def __post_init__(self) -> None:
        C.integer("rod.elements", self.elements, low=1, high=MAX_ELEMENTS)

    @property
    def length(self) -> float:
        return self.geometry.length


@dataclass(frozen=True)
class Simulation:
    """The dynamic run: end time (s), tolerances, output sampling (s), BDF settings and
    the initial state ("static": equilibrium under the loads at t = 0-; "reference": the
    stress-free reference at rest). ``max_order`` None: :meth:`Problem.bdf_max_order`.
    ``error_control``: what the BDF local error test controls, "state" (every unknown),
    "configuration" (positions, rotations, internal strains; the velocities are left to
    the corrector, as IDA's suppressalg leaves algebraic unknowns) or "auto"
    (:meth:`Problem.error_control`: configuration for a generalized Maxwell rod).
    ``centreline_frames``: node positions kept at this many equally spaced times from 0
    to t_end (the deformed centreline for ``kvrod plot``; 0: none)."""

    t_end: float = 10.0
    rtol: float = 1e-6
    atol: float | None = None
    output_step: float = 0.005
    max_order: int | None = None
    min_step: float = 0.0
    initial: str = "static"
    centreline_frames: int = 101
    error_control: str = "auto"

    def __post_init__(self) -> None:
        C.positive("simulation.t_end", self.t_end)
        C.number("simulation.rtol", self.rtol, low=RTOL_MIN, high=1.0, high_incl=False)
        if self.atol is not None:
            C.number("simulation.atol", self.atol, low=ATOL_MIN, high=1.0, high_incl=False)
        C.positive("simulation.output_step", self.output_step)
        if self.t_end / self.output_step > MAX_SAMPLES:
            raise ParameterError("simulation.output_step", self.output_step,
                                 f">= t_end/{MAX_SAMPLES:.0e} = {self.t_end / MAX_SAMPLES:.3g} s "
                                 "(at most 1e7 samples)")
        if self.max_order is not None:
            C.integer("simulation.max_order", self.max_order, low=1, high=5)
        C.number("simulation.min_step", self.min_step, low=0.0, high=self.t_end)
        C.choice("simulation.initial", self.initial, ("static", "reference"))
        C.choice("simulation.error_control", self.error_control, ERROR_CONTROLS)
        if C.integer("simulation.centreline_frames", self.centreline_frames, low=0,
                     high=MAX_FRAMES) == 1:
            raise ParameterError("simulation.centreline_frames", 1,
                                 f"0 (none) or 2 ... {MAX_FRAMES}")


@dataclass(frozen=True)
class Statics:
    """Static equilibrium by Newton with ``load_steps`` initial load increments
    (continuation); ``report``: load factors in (0, 1) at which the end positions are
    recorded on the way (``static.path`` of the summary; the full load is always
    recorded), e.g. ``[0.5, 0.75]`` for 300 and 450 of a 600 load."""

    load_steps: int = 10
    report: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        C.integer("statics.load_steps", self.load_steps, low=1, high=10_000)
        if isinstance(self.report, (str, bytes, Mapping)) or not hasattr(self.report,
                                                                         "__len__"):
            raise ParameterError("statics.report", self.report,
                                 "a list of load factors in (0, 1)")
        vals = tuple(C.number(f"statics.report[{i}]", v, low=0.0, high=1.0, low_incl=False,
                              high_incl=False) for i, v in enumerate(self.report))
        object.__setattr__(self, "report", tuple(sorted(set(vals))))


MAXIMA = tuple(f"{e}.{c}" for e in ("end", "start") for c in "xyz")


@dataclass(frozen=True)
class Analysis:
    """What to analyse in a run: ``maxima`` of one end coordinate ("end.x", ...; their
    logarithmic decrements and damping ratios), or None."""

    maxima: str | None = None

    def __post_init__(self) -> None:
        if self.maxima is not None:
            C.choice("analysis.maxima", self.maxima, MAXIMA)


#: a section's coupling coefficient |M_ij| / sqrt(M_ii M_jj) (and mass-centre offset over
#: the radius of gyration, product of inertia over sqrt(I11 I22)) below which a closed-form
#: prediction takes the bending as uncoupled: a finite-element section's round-off
#: couplings (~1e-7 for a circular cable) change omega by far less
COUPLING_TOL = 1e-5


@dataclass(frozen=True)
class Problem:
    """A rod problem (see the module docstring)."""

    name: str = "problem"
    description: str = ""
    rod: Rod = field(default_factory=Rod)
    section: Section = field(default_factory=lambda: section_from_mapping(
        {"kind": "rectangle", "width": 0.01, "height": 0.01}))
    #: None: the default Kelvin-Voigt material for a homogeneous section; a composite
    #: section has none (its regions name their materials)
    material: Material | None = None
    start: End = field(default_factory=lambda: End("clamped"))
    end: End = field(default_factory=End)
    loads: tuple[Load, ...] = ()
    simulation: Simulation = field(default_factory=Simulation)
    statics: Statics = field(default_factory=Statics)
    analysis: Analysis = field(default_factory=Analysis)
    base: Path | None = field(default=None, compare=False, repr=False)
    #: stretches of the rod with their own section or material (runtime.problem.zones)
    zones: tuple[Any, ...] = ()
    #: arc lengths (m) of the named points of an assembly on this rod (its joints', bodies'
    #: and point loads' points: runtime.problem.assembly); the rod has a node at each. A
    #: single-rod file has none (and to_mapping does not write them)
    points: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        from runtime.problem.sections import LENGTH_MAX, LENGTH_MIN, LENGTH_RANGE

        composite = isinstance(self.section, Composite)
        if self.material is None and not composite:
            object.__setattr__(self, "material", material_from_mapping({}))
        if composite and self.material is not None:
            raise ParameterError("material", self.material.to_mapping(), BESIDE_COMPOSITE)
        N = self.rod.elements
        if not LENGTH_MIN <= self.rod.length <= LENGTH_MAX:
            raise ParameterError("rod.length", self.rod.length, LENGTH_RANGE)
        if not composite:
            self._check_matrices()
        object.__setattr__(self, "points", tuple(
            C.number("points", s, low=0.0, high=self.rod.length * (1 + 1e-12),
                     allowed=f"arc lengths 0 ... {self.rod.length:g} m (the rod length)")
            for s in self.points))
        for ld in self.loads:
            if ld.s is not None and ld.s > self.rod.length * (1 + 1e-12):
                raise ParameterError("loads.s", ld.s, f"0 ... rod length {self.rod.length:g} m")
            if isinstance(ld.at, int) and not 0 <= ld.at <= N:
                raise ParameterError("loads.at", ld.at, f"a node 0 ... {N} (rod.elements)")
        if self.simulation.initial == "reference" and self.loads and all(
                ld.kind == "gravity" for ld in self.loads):
            pass  # a falling rod (pendulum): nothing to check
        self._check_zone_nodes()
        frames = self.simulation.centreline_frames
        if frames * 3 * (N + 1) > MAX_FRAME_VALUES:
            raise ParameterError("simulation.centreline_frames", frames,
                                 f"0 ... {int(MAX_FRAME_VALUES // (3 * (N + 1)))} for "
                                 f"{N} elements (at most {MAX_FRAME_VALUES:.0e} stored "
                                 "node coordinates)")
        if composite:
            # the checks below need the rod's matrices, which a composite section does not
            # give the kernels yet (check_simulable refuses its runs)
            self._check_positions()
            self._check_input_frequencies()
            return
        self._check_periods()
        self._check_viscous_rate()
        self._check_maxwell_springs()
        self._check_load_magnitudes()
        self._check_positions()
        self._check_input_frequencies()
        self._check_t_end()

    def _check_zone_nodes(self) -> None:
        """The nodes (one at every zone boundary and point load's s) exist, and every zone
        holds a segment: a zone shorter than the nodes' snapping tolerance would change
        nothing."""
        s = self.node_arc_lengths()
        mid = 0.5 * (s[:-1] + s[1:])
        for z in self.zones:
            if not np.any((mid >= z.start) & (mid < z.end)):
                raise ParameterError(
                    f"zones[{z.index}]", f"from = {z.start:g}, to = {z.end:g} m",
                    f"a stretch longer than {NODE_SNAP_RTOL:g} of the rod length (nodes go "
                    "at its boundaries; this one is shorter than their tolerance)")

    def _check_periods(self) -> None:
        periods = self.simulation.t_end * self.characteristic_frequency() / (2 * math.pi)
        if periods > MAX_PERIODS:
            raise ParameterError(
                "simulation.t_end", self.simulation.t_end,
                f"at most {MAX_PERIODS:.0e} periods of the rod's first bending mode "
                f"({MAX_PERIODS * 2 * math.pi / self.characteristic_frequency():.3g} s for "
                f"this rod: length {self.rod.length:g} m, density "
                f"{getattr(self.material, 'density', float('nan')):g} kg/m^3, E "
                f"{getattr(self.material, 'youngs_modulus', float('nan')):g} Pa); the run "
                f"would need more than {50 * periods:.2g} steps")

    def _check_t_end(self) -> None:
        w_max = math.sqrt(self.element_rates()[0])
        t_min = math.sqrt(float(np.finfo(float).eps)) / w_max
        soft = (not isinstance(self.section, (GivenStiffness, Composite))
                and getattr(self.material, "youngs_modulus", 1.0) < SOFT_E_MIN)
        if self.simulation.t_end < t_min and not soft:   # (soft: see SOFT_E_MIN)
            source = ("its section's matrices" if isinstance(self.section, Composite) else
                      f"density {getattr(self.material, 'density', float('nan')):g} kg/m^3, "
                      f"material.youngs_modulus = "
                      f"{getattr(self.material, 'youngs_modulus', float('nan')):g} Pa")
            raise ParameterError(
                "simulation.t_end", self.simulation.t_end,
                f">= sqrt(eps) / omega_max = {t_min:.3g} s for this rod (omega_max = "
                f"{w_max:.4g} rad/s, its stiffest element mode at N = {self.rod.elements}, "
                f"from length {self.rod.length:g} m, {source}): in a "
                "shorter run not even that mode moves the rod by more than round-off (a "
                "displacement ~ (omega t)^2 of its scale)")

    @property
    def damping(self) -> str:
        """The rod viscosity route, ``section.damping``: "consistent" or "naive"."""
        if isinstance(self.section, Composite):
            return self.section.damping
        return getattr(self.material, "damping", "consistent")

    def describe_material(self) -> str:
        """One line for reports: the material's retardation times, or a composite
        section's regions and its damping route."""
        if isinstance(self.section, Composite):
            names = ", ".join(dict.fromkeys(r.material for r in self.section.regions))
            return (f"composite section of {names} (Kelvin-Voigt regions, "
                    f"{self.section.damping} rod viscosity, tau_E = {self.tau_E:.6g} s)")
        if self._given_viscosity():
            return (f"6x6 stiffness and viscosity matrices of the section "
                    f"({self.damping}; tau_E = V33 / K33 = {self.tau_E:.6g} s)")
        return self.material.describe()

    def relaxation_terms(self) -> int:
        """The number B of the rod's relaxation terms (generalized Maxwell; else 0)."""
        return len(self._end_matrices().get("theta", ()))

    @property
    def tau_E(self) -> float:
        """The extensional retardation time (s): the material's tau_E (eq. (6)), or for a
        composite section V33 / K33 of its rod matrices (the same number for a
        homogeneous section)."""
        if isinstance(self.section, Composite) or self._given_viscosity():
            m = self._uniform_matrices()
            return float(m["V_F"][0, 2] / m["C_F"][0, 2])
        return float(self.material.tau_E)

    def _given_viscosity(self) -> bool:
        """A ``stiffness`` section with its own ``viscosity_matrix`` (the material's
        retardation times are then 0: :func:`section_and_material`)."""
        return (isinstance(self.section, GivenStiffness)
                and self.section.viscosity_matrix is not None)

    def check_simulable(self) -> None:
        """Raise :class:`~runtime.errors.ParameterError` for a problem the rod cannot
        run. Every command that simulates, solves statically, analyses modes or sweeps
        calls it before it writes anything. A composite section is checked here rather
        than on construction: its rod matrices need its finite-element analysis (0.2 ... 2
        s, once per distinct section in a process), which reading or writing the problem
        does not; here they are computed and the checks that need them run (a naive
        viscosity that is not symmetric is refused, naming ``section.damping``)."""
        if isinstance(self.section, Composite) and not self.__dict__.get("_checked"):
            self._end_matrices()
            self._check_matrices()
            self._check_periods()
            self._check_viscous_rate()
            self._check_load_magnitudes()
            self._check_t_end()
            object.__setattr__(self, "_checked", True)

    def _check_maxwell_springs(self) -> None:
        """A generalized Maxwell rod: without an equilibrium spring (a Maxwell fluid) no
        static equilibrium exists under loads; and its instantaneous (glassy) modulus may
        exceed the equilibrium one by at most GLASSY_RATIO_MAX, beyond which the relaxed
        stiffness is lost to round-off next to the branches'."""
        mat = self.material
        if not isinstance(mat, GeneralizedMaxwell):
            return
        if mat.youngs_modulus == 0.0:
            if self.loads and self.simulation.initial == "static":
                raise ParameterError(
                    "simulation.initial", "static", '"reference" for a Maxwell fluid '
                    "(material.youngs_modulus = 0: no equilibrium spring, so no static "
                    "equilibrium under the loads; start from the reference at rest)")
            return
        G_inf, K_inf, G_j, K_j, _ = mat.moduli       # of the 3-D solid (Pa)
        with np.errstate(over="ignore", invalid="ignore"):
            ratio = max((G_inf + float(np.sum(G_j))) / G_inf,
                        (K_inf + float(np.sum(K_j))) / K_inf)
        if not ratio <= GLASSY_RATIO_MAX:
            k = int(np.argmax([b.shear_modulus + b.bulk_modulus for b in mat.branches]))
            raise ParameterError(
                f"material.branches.{k}", mat.branches[k].to_mapping(),
                f"branches whose springs keep the glassy moduli at most "
                f"{GLASSY_RATIO_MAX:.0e} times the equilibrium ones (G_inf = {G_inf:g} Pa, "
                f"K_inf = {K_inf:g} Pa; here "
                f"{ratio:.3g} times): beyond it the relaxed stiffness is lost to round-off")

    def _check_matrices(self) -> None:
        """The rod's stiffness and inertia must be finite and positive numbers."""
        m = self._end_matrices()
        for key in ("C_F", "C_M", "rhoA", "rhoI"):
            v = np.asarray(m[key], dtype=float)
            if not (np.all(np.isfinite(v)) and np.all(v > 0)):
                what = "stiffness" if key.startswith("C") else "mass or rotary inertia"
                raise ParameterError(
                    "section", self.section.to_mapping(),
                    f"a section and material whose {what} ({key}) is a finite number > 0 "
                    f"(here {key} = {float(np.min(v)):.3g} ... {float(np.max(v)):.3g}; material "
                    f"E = {getattr(self.material, 'youngs_modulus', float('nan')):g} Pa, "
                    f"density {getattr(self.material, 'density', float('nan')):g} kg/m^3)")

    def _check_positions(self) -> None:
        """Positions (origin, prescribed translations) and clamp rotations small enough
        that round-off leaves the element strains meaningful: |r| eps <= 1e-8 h_min (a
        strain error of 1e-8; h_min = L/N on a uniform grid), |angle| eps <= 1e-8 rad."""
        eps = float(np.finfo(float).eps)
        r_max = 1e-8 * self.shortest_element() / eps
        origin = getattr(self.rod.geometry, "origin", (0.0, 0.0, 0.0))
        if math.hypot(*origin) > r_max:
            raise ParameterError("rod.geometry.origin", list(origin),
                                 f"|origin| <= 1e-8 (L/N)/eps = {r_max:.3g} m for this rod: "
                                 "farther out, round-off of the coordinates swamps the "
                                 "elements' strains")
        a_max = math.degrees(1e-8 / eps)
        for name, end in (("start", self.start), ("end", self.end)):
            mo = end.motion
            if mo is None:
                continue
            with np.errstate(over="ignore"):
                tr = math.hypot(*mo.translation) * _time_peak(mo.translation_time)
                ang = abs(mo.rotation_angle) * _time_peak(mo.rotation_time)
            if tr > r_max:
                raise ParameterError(f"{name}.motion.translation", list(mo.translation),
                                     f"|translation| x its time function's peak <= 1e-8 "
                                     f"(L/N)/eps = {r_max:.3g} m for this rod (here "
                                     f"{tr:.3g} m): farther, round-off of the coordinates "
                                     "swamps the elements' strains")
            if ang > a_max:
                raise ParameterError(f"{name}.motion.rotation_angle", mo.rotation_angle,
                                     f"|rotation_angle| x its time function's peak <= "
                                     f"{a_max:.3g} deg (1e-8 rad / eps: the round-off of a "
                                     "larger angle exceeds 1e-8 rad)")

    def _check_input_frequencies(self) -> None:
        """A harmonic input may hold at most MAX_PERIODS periods in t_end (a run resolves
        each period with tens of steps, like the rod's own modes)."""
        inputs = [(f"loads.{k}.time", ld.time) for k, ld in enumerate(self.loads)]
        for name, end in (("start", self.start), ("end", self.end)):
            if end.motion is not None:
                inputs += [(f"{name}.motion.translation_time", end.motion.translation_time),
                           (f"{name}.motion.rotation_time", end.motion.rotation_time)]
        for name, tf in inputs:
            if getattr(tf, "kind", "") != "harmonic":
                continue
            with np.errstate(over="ignore"):
                periods = self.simulation.t_end * float(tf.frequency)
            if periods > MAX_PERIODS:
                raise ParameterError(f"{name}.frequency", tf.frequency,
                                     f"at most {MAX_PERIODS:.0e} periods in t_end = "
                                     f"{self.simulation.t_end:g} s, i.e. <= "
                                     f"{MAX_PERIODS / self.simulation.t_end:.3g} Hz (each "
                                     "period needs tens of integrator steps)")

    def _check_load_magnitudes(self) -> None:
        if (not isinstance(self.section, GivenStiffness)
                and getattr(self.material, "youngs_modulus", 1.0) < SOFT_E_MIN):
            # the material is the likely culprit, not the load: the statics refuse it
            # naming material.youngs_modulus (runtime.model.rigid.check_stiffness)
            return
        m = self._end_matrices()
        EA = float(np.min(m["C_F"]))
        EI = float(np.min(m["C_M"]))
        rhoA = float(np.max(m["rhoA"]))
        L = self.rod.length
        for k, ld in enumerate(self.loads):
            size = math.hypot(*ld.vector)          # no overflow of the squares
            peak = _time_peak(ld.time)
            scale = {"force": 1 / EA, "distributed": L / EA, "gravity": rhoA * L / EA,
                     "moment": L / EI}[ld.kind]
            with np.errstate(over="ignore"):
                measure = size * peak * scale
            if measure <= LOAD_STRAIN_MAX:
                continue
            what = "rotation (rad) |M| L / min(EI, GJ)" if ld.kind == "moment" else (
                "strain |F| / min(EA, GA)" if ld.kind == "force" else
                "strain |q| L / min(EA, GA)" if ld.kind == "distributed" else
                "strain rho A |g| L / min(EA, GA)")
            name, value = ((f"loads.{k}.time", ld.time.to_mapping())
                           if size * scale <= LOAD_STRAIN_MAX and peak > 1 else
                           (f"loads.{k}.vector", list(ld.vector)))
            raise ParameterError(
                name, value, f"a load whose {what} stays below {LOAD_STRAIN_MAX:.0e} (this "
                f"load: {measure:.3g}, its time function peaking at {peak:.3g}; the rod "
                f"carries at most {LOAD_STRAIN_MAX / scale:.3g} {_LOAD_UNITS[ld.kind]} "
                f"meaningfully: its softest stiffness is {EI if ld.kind == 'moment' else EA:.3g} "
                f"{'N m^2' if ld.kind == 'moment' else 'N'}, from the section and "
                f"material.youngs_modulus = {getattr(self.material, 'youngs_modulus', 0):g} "
                "Pa)")

    def element_rates(self) -> tuple[float, float]:
        """(omega_max^2 in 1/s^2, viscous rate in 1/s) of the stiffest element mode: the
        largest stiffness-to-inertia ratio over the rod's element modes (extension,
        shear, bending and torsion of one element of length L/N, and the rotation of a
        section against its shear stiffness, kappa G A / (rho I)), from C and from the
        Kelvin-Voigt V = diag(tau) C (eqs. (7), (9)); evaluated at both ends and the middle
        (tapers are linear). A generalized Maxwell material has no V: rate 0."""
        m = self._end_matrices()
        N = self.rod.elements
        h_min = self.shortest_element()
        k2 = ((N / self.rod.length) ** 2 if h_min == self.rod.length / N
              else 1.0 / h_min**2)
        rhoA, rhoI = m["rhoA"][:, None], m["rhoI"]
        rhoI12 = np.min(rhoI[:, :2], axis=1)[:, None]

        def rate(F: np.ndarray, M: np.ndarray) -> float:
            with np.errstate(over="ignore", invalid="ignore"):
                r = np.concatenate([(F / rhoA * k2).ravel(), (M / rhoI * k2).ravel(),
                                    (F[:, :2] / rhoI12).ravel()])
            return float(np.max(r)) if np.all(np.isfinite(r)) else math.inf

        if "V_F" not in m or isinstance(self.material, GeneralizedMaxwell):
            return rate(m["C_F"], m["C_M"]), 0.0
        return rate(m["C_F"], m["C_M"]), rate(m["V_F"], m["V_M"])

    def _check_viscous_rate(self) -> None:
        if isinstance(self.material, GeneralizedMaxwell):
            return
        w2, lam = self.element_rates()
        if lam <= VISCOUS_RATE_MAX:
            return
        mat = self.material
        value: Any
        if isinstance(self.section, Composite):
            # the region material with the longest retardation time (max |V| / max |C|);
            # the composite has no [material] (an internal error used to follow)
            mats = self.section.used_materials()
            worst = max(mats, key=lambda k: float(np.max(np.abs(mats[k].viscosity)))
                        / float(np.max(np.abs(mats[k].stiffness))))
            name, value = f"materials.{worst}", self.section.materials_mapping()[worst]
        elif self._given_viscosity():
            name, value = "section.viscosity_matrix", "given"
        elif mat.tau_S == mat.tau_B:
            name, value = "material.tau", mat.tau_S
        elif mat.tau_S > mat.tau_B:
            name, value = "material.tau_S", mat.tau_S
        else:
            name, value = "material.tau_B", mat.tau_B
        tau = lam / w2 if isinstance(value, (str, dict)) else value   # the equivalent tau
        raise ParameterError(
            name, value, f"retardation times with tau * omega_max^2 <= {VISCOUS_RATE_MAX:.2g} "
            f"1/s, i.e. tau <= {VISCOUS_RATE_MAX / w2:.3g} s for this rod (N = "
            f"{self.rod.elements} elements: its stiffest element mode has omega_max^2 = "
            f"{w2:.3g} 1/s^2); beyond it the viscous forces exceed the inertia by more than "
            "1/(10 eps) and the integrator loses the inertia to round-off (the first mode's "
            f"damping ratio would be {self.characteristic_frequency() * tau / 2:.3g})")

    # -- derived figures ---------------------------------------------------------------
    def error_control(self) -> str:
        """What the BDF error test controls: ``simulation.error_control``, "auto" resolved
        to "configuration" for a generalized Maxwell material and "state" otherwise.

        Why: a Maxwell rod's glassy high-frequency modes are stiff and lightly damped
        (decay rate sum_b (E_b/tau_b) / (2 E_glassy), whatever their frequency); a release
        sets them ringing with velocities of the order of the motion's, and an error
        test on those velocities resolves the ringing (h ~ 1e-6 s at N = 50) long after
        the positions have stopped noticing it. Structural integrators control the
        configuration; the velocities follow from it through the corrector. For a
        Kelvin-Voigt rod every mode above the first few is overdamped and the velocity
        test costs nothing, while leaving it out loosened the energy audit (measured:
        2.3e-4 against 2.45e-5 on the paper's cantilever), so the state is controlled.
        docs/design.md, "Maxwell rods at matched accuracy", has the measurements.
        """
        choice = self.simulation.error_control
        if choice != "auto":
            return choice
        return "configuration" if isinstance(self.material, GeneralizedMaxwell) else "state"

    def bdf_max_order(self) -> int:
        """The highest BDF order of a run: ``simulation.max_order`` if given, else 5.

        A generalized Maxwell rod's glassy high-frequency modes are lightly damped and
        BDF3-5 are not A-stable: on steps too small to damp them (``|h| sigma_g < D_k``) the
        integrator itself keeps the order at 2
        (:class:`~runtime.solvers.bdf.BDF`'s ``stiff_decay_rate``). Before that bound the
        default here was 2 for a Maxwell rod (157694 steps at order 5, 26816 at order 2
        on examples/maxwell_cantilever.toml, N = 50, 10 s); with it the state-controlled
        run takes 24556 steps at order 5, the configuration-controlled default 3261 (3303
        since the internal strains left the Newton system: its round-off changed).
        """
        if self.simulation.max_order is not None:
            return self.simulation.max_order
        return 5

    def breakpoints(self) -> tuple[float, ...]:
        """Arc lengths (m) where the rod must have a node: the zone boundaries, the
        points where point loads act by arc length (``loads.s``) and an assembly's named
        points on the rod (``points``)."""
        out = [b for z in self.zones for b in (z.start, z.end)]
        out += [ld.s for ld in self.loads if ld.s is not None]
        out += list(self.points)
        return tuple(out)

    def node_arc_lengths(self) -> np.ndarray:
        """Arc lengths (N+1,) of the nodes (m): uniform, or with a node at every
        breakpoint (:meth:`breakpoints`; ``runtime.problem.geometry.node_arc_lengths``)."""
        s = self.__dict__.get("_s_nodes")
        if s is None:
            s = node_arc_lengths(self.rod.length, self.rod.elements, self.breakpoints())
            s.setflags(write=False)
            object.__setattr__(self, "_s_nodes", s)
        return s

    def segment_fractions(self) -> np.ndarray:
        """The segments' midpoints (N,) as fractions of the rod length, where their
        matrices are taken (uniform: ``(i + 1/2) / N``, the arithmetic of a rod whose
        nodes nothing moved)."""
        N = self.rod.elements
        s = self.node_arc_lengths()
        if np.array_equal(s, np.arange(N + 1) * (self.rod.length / N)):
            return (np.arange(N) + 0.5) / N
        return 0.5 * (s[:-1] + s[1:]) / self.rod.length

    def shortest_element(self) -> float:
        """The shortest element's length (m): L/N on a uniform grid."""
        N = self.rod.elements
        s = self.node_arc_lengths()
        if np.array_equal(s, np.arange(N + 1) * (self.rod.length / N)):
            return self.rod.length / N
        return float(np.min(np.diff(s)))

    def segment_matrices(self) -> dict[str, np.ndarray]:
        """Per segment: C_F, C_M, V_F, V_M diagonals (N, 3), rhoA (N,), rhoI (N, 3); a
        coupled section also K6, V6 (N, 6, 6), rhoJ (N, 3, 3), mass_centre (N, 2)
        (:mod:`runtime.problem.coupled`), at the segments' midpoints."""
        self.check_simulable()
        x = self.segment_fractions()
        m = self._matrices_at(x)
        if self.zones:
            from runtime.problem.zones import apply_zones

            m = apply_zones(m, x * self.rod.length, self.zones, self._zone_matrices)
        return m

    @staticmethod
    def _zone_matrices(zone: Any, x: np.ndarray) -> dict[str, np.ndarray]:
        if isinstance(zone.section, Composite):
            from runtime.problem.coupled import composite_matrices

            return composite_matrices(zone.section, np.size(x))
        return zone.material.rod_matrices(zone.section, x)

    def _matrices_at(self, x: np.ndarray) -> dict[str, np.ndarray]:
        if isinstance(self.section, Composite):
            from runtime.problem.coupled import composite_matrices

            return composite_matrices(self.section, np.size(x))
        return self.material.rod_matrices(self.section, x)

    def _end_matrices(self) -> dict[str, np.ndarray]:
        """The rod matrices at the start, middle and end (x = 0, 1/2, 1), computed once
        (the checks of every new problem use them)."""
        m = self.__dict__.get("_m3")
        if m is None:
            x3 = np.array([0.0, 0.5, 1.0])
            m = self._matrices_at(x3)
            if self.zones:         # the checks see every zone's ends and middle too
                parts = [m] + [self._zone_matrices(z, x3) for z in self.zones]
                keys = set.intersection(*(set(p) for p in parts)) - {"theta", "segb", "jntb"}
                m = {k: np.concatenate([p[k] for p in parts]) for k in keys
                     } | {k: v for k, v in m.items() if k in ("theta", "segb", "jntb")}
            object.__setattr__(self, "_m3", m)
        return m

    def _uniform_matrices(self) -> dict[str, np.ndarray]:
        return {k: v[1:2] if k != "theta" else v for k, v in self._end_matrices().items()}

    def characteristic_frequency(self) -> float:
        """Euler-Bernoulli clamped-free first bending frequency (rad/s) of the rod at mid
        length, with its softer bending stiffness: the time scale of tolerances and
        guards (an estimate for other ends and shapes)."""
        m = self._uniform_matrices()
        EI = float(min(m["C_M"][0, 0], m["C_M"][0, 1]))
        rhoA = float(m["rhoA"][0])
        return BETA1_L**2 * math.sqrt(EI / (rhoA * self.rod.length**4))

    def uniform_equivalent(self) -> Problem | None:
        """The problem as a rod of one section and material, where it is one: itself
        without zones; with zones, the problem whose section and material are the zone's
        when one zone covers the whole rod (its segments all take the zone's); None when
        zones make the rod vary along its length (no closed form applies)."""
        if not self.zones:
            return self
        tol = 1e-12 * self.rod.length
        if len(self.zones) == 1:
            z = self.zones[0]
            if z.start <= tol and z.end >= self.rod.length - tol:
                return replace(self, section=z.section,
                               material=None if isinstance(z.section, Composite)
                               else z.material, zones=())
        return None

    def linear_prediction_note(self) -> str | None:
        """Why :meth:`linear_prediction` is None (in words), or None when it is not."""
        return self._linear_prediction()[1]

    def linear_prediction(self) -> dict[str, Any] | None:
        """For a straight, uniform, clamped-free rod whose end maxima are analysed: the
        Euler-Bernoulli first bending mode in the direction of the maxima (``mode`` names
        it) and its Kelvin-Voigt damping ratio omega_1 tau_B / 2 (tau_B = V/C of that
        bending stiffness, the consistent or naive one the rod takes); for a generalized
        Maxwell material the mode with the complex modulus E*(i omega_1) at its own
        frequency and zeta = Im E* / (2 Re E*). None where no closed form applies (the
        reason: :meth:`linear_prediction_note`): other supports, shapes, end motion,
        tapers, zones that make the rod vary, loads left on the rod after release that
        act along its axis (a hanging rod's tension) or moments, a section whose bending
        in that direction couples to other strains (full 6x6 matrices) or whose mass centre
        or product of inertia couple it to twist."""
        return self._linear_prediction()[0]

    def _linear_prediction(self) -> tuple[dict[str, Any] | None, str | None]:
        which = self.analysis.maxima
        if not (which and which.startswith("end")):
            return None, "analysis.maxima does not name a coordinate of the free end"
        if not (isinstance(self.rod.geometry, Straight) and self.start.kind == "clamped"
                and self.start.motion is None and self.end.kind == "free"):
            return None, ("the closed form is for a straight cantilever (clamped at s = 0 "
                          "without motion, free at s = L)")
        if getattr(self.section, "tapered", False) or getattr(
                self.material, "youngs_modulus_end", None) is not None or getattr(
                self.material, "density_end", None) is not None:
            return None, "the rod is tapered: its properties vary along its length"
        t_end = self.simulation.t_end
        tangent = np.asarray(self.rod.geometry._basis()[:, 2], dtype=float)
        for k, ld in enumerate(self.loads):
            v = np.asarray(ld.vector, dtype=float) * ld.time.value_at(t_end)
            axial = abs(float(v @ tangent)) if ld.kind != "moment" else float(np.linalg.norm(v))
            if axial > 1e-9 * max(float(np.linalg.norm(v)), 1e-300) and np.any(v):
                return None, (f"loads[{k}] ({ld.kind}) still acts at t_end and stresses the "
                              "rod along its axis (or twists it): its frequencies are not the "
                              "unloaded beam's; see kvrod modes --deformed")
        eq = self.uniform_equivalent()
        if eq is None:
            return None, "zones make the rod's section or material vary along its length"
        if eq is not self:
            return eq._linear_prediction()
        m = self.segment_matrices() if self.zones else self._uniform_matrices()
        basis = self.rod.geometry._basis()
        e = np.eye(3)["xyz".index(which[-1])]
        # a displacement along d1 bends about d2 (E I2), along d2 about d1 (E I1)
        along_d1 = abs(float(e @ basis[:, 0])) >= abs(float(e @ basis[:, 1]))
        k = 4 if along_d1 else 3              # K2 or K1 in the 6x6 strain order
        g = 0 if along_d1 else 1              # the shear in the same plane: Gamma1 / Gamma2
        if "K6" in m:
            K6, V6 = m["K6"][0], m["V6"][0]
            for M6, what in ((K6, "stiffness"), (V6, "viscosity")):
                d = np.sqrt(np.abs(np.diag(M6)))
                with np.errstate(divide="ignore", invalid="ignore"):
                    corr = np.abs(M6[k]) / (d[k] * d)       # coupling coefficients
                corr[[k, g]] = 0.0
                if np.nanmax(corr) > COUPLING_TOL:
                    return None, (f"the section's {what} couples the bending in "
                                  f"{which} to other strains (its 6x6 matrix): no closed "
                                  "form; see kvrod modes")
            ec = np.asarray(m["mass_centre"][0], dtype=float)
            J = np.asarray(m["rhoJ"][0], dtype=float)
            gyration = math.sqrt(abs(J[2, 2]) / float(m["rhoA"][0]))
            if (np.hypot(*ec[:2]) > COUPLING_TOL * gyration
                    or abs(J[0, 1]) > COUPLING_TOL * math.sqrt(abs(J[0, 0] * J[1, 1]))):
                return None, ("the section's mass centre or product of inertia couples its "
                              "bending to twist: no closed form; see kvrod modes")
        plane = "d1" if along_d1 else "d2"
        axis = "d2 (E I2)" if along_d1 else "d1 (E I1)"
        EI = float(m["C_M"][0, 1] if along_d1 else m["C_M"][0, 0])
        rhoAL4 = float(m["rhoA"][0]) * self.rod.length**4
        if isinstance(self.material, GeneralizedMaxwell):
            # the complex modulus at the mode's frequency (fixed point on omega):
            # zeta = Im E*(i w) / (2 Re E*(i w)); tau: the equivalent 2 zeta / omega
            r = self.material.rod_relaxation()
            E_g = r.E_inf + float(r.E.sum())          # C_M holds the instantaneous E I
            EI_over_E = EI / E_g if E_g > 0 else 0.0
            omega = BETA1_L**2 * math.sqrt(EI / rhoAL4)
            for _ in range(50):
                Es = complex(self.material.complex_moduli(omega)[0])
                new = BETA1_L**2 * math.sqrt(max(Es.real, 0.0) * EI_over_E / rhoAL4)
                if abs(new - omega) <= 1e-12 * omega:
                    break
                omega = new
            zeta = Es.imag / (2 * Es.real) if Es.real > 0 else math.inf
            tau = 2 * zeta / omega if omega > 0 else math.inf
            formula = "Im E*(i omega_1) / (2 Re E*(i omega_1))"
        else:
            tau = float(m["V_M"][0, 1] / m["C_M"][0, 1] if along_d1 else
                        m["V_M"][0, 0] / m["C_M"][0, 0])
            omega = BETA1_L**2 * math.sqrt(EI / rhoAL4)
            zeta = omega * tau / 2.0
            formula = "omega_1 tau / 2"
        mode = (f"first bending mode of the clamped-free Euler-Bernoulli beam in {which} "
                f"(along {plane}, bending about {axis})")
        return {"formula": formula, "mode": mode, "omega_1": omega,
                "period_1": 2 * math.pi / omega, "tau": tau, "zeta_1": zeta,
                "log_decrement_1": 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
                if zeta < 1 else math.inf}, None

    # -- mappings ------------------------------------------------------------------------
    def to_mapping(self) -> dict[str, Any]:
        """The resolved problem as a TOML-ready table (numbers, strings, lists)."""
        g = self.rod.geometry
        rod: dict[str, Any] = {"elements": self.rod.elements, "geometry": g.to_mapping()}
        if isinstance(g, Straight):
            rod["length"] = g.rod_length
        section = {**self.section.to_mapping(), "damping": self.damping}
        if isinstance(self.section, Composite):
            stuff: dict[str, Any] = {"materials": self.section.materials_mapping()}
        else:
            material = self.material.to_mapping()
            material.pop("damping", None)               # the key is section.damping
            stuff = {"material": material}
        if self.zones:
            stuff["zones"] = [z.to_mapping() for z in self.zones]
            for z in self.zones:
                if isinstance(z.section, Composite):
                    stuff.setdefault("materials", {}).update(z.section.materials_mapping())
        return {"name": self.name, "description": self.description, "rod": rod,
                "section": section, **stuff,
                "start": self.start.to_mapping(), "end": self.end.to_mapping(),
                "loads": [ld.to_mapping() for ld in self.loads],
                "simulation": {k: v for k, v in vars(self.simulation).items()
                               if v is not None},
                "statics": {"load_steps": self.statics.load_steps,
                            **({"report": list(self.statics.report)}
                               if self.statics.report else {})},
                "analysis": {k: v for k, v in vars(self.analysis).items() if v is not None}}

    @classmethod
    def from_mapping(cls, m: Mapping[str, Any], base: Path | None = None,
                     name: str = "problem", points: tuple[float, ...] = ()) -> Problem:
        """Build and check a problem from a TOML table (see the module docstring);
        ``points``: the arc lengths of an assembly's named points on the rod (the
        field ``points``, not a key of the table)."""
        m = C.table("", m)
        C.no_unknown_keys("", m, TOP_KEYS)
        rod_m = dict(C.table("rod", m.get("rod", {})))
        C.no_unknown_keys("rod", rod_m, ("length", "elements", "geometry"))
        length = C.positive("rod.length", rod_m["length"]) if "length" in rod_m else None
        geometry = geometry_from_mapping(rod_m.get("geometry"), length, base)
        rod = Rod(geometry, C.integer("rod.elements", rod_m.get("elements", 50), low=1,
                                      high=MAX_ELEMENTS))
        loads_m = m.get("loads", [])
        if not isinstance(loads_m, list):
            raise ParameterError("loads", loads_m, "an array of tables [[loads]]")
        loads = tuple(load_from_mapping(f"loads[{i}]", ld, base)
                      for i, ld in enumerate(loads_m))
        from runtime.problem.section_file import with_section_file

        m = with_section_file(m, base)
        zones_m = m.get("zones")
        zone_composite = isinstance(zones_m, list) and any(
            isinstance(z, Mapping) and isinstance(z.get("section"), Mapping)
            and z["section"].get("kind") == "composite" for z in zones_m)
        top = dict(m)
        if zone_composite and "materials" in m and C.table(
                "section", m.get("section") or {}).get("kind") != "composite":
            top.pop("materials")         # the zones' composite sections name them
        section, material = section_and_material(top)
        from runtime.problem.zones import zones_from_mapping

        zones = zones_from_mapping(zones_m, m, rod.length)
        return cls(
            name=C.string("name", m.get("name", name)),
            description=str(m.get("description", "")),
            rod=rod,
            section=section,
            material=material,
            start=end_from_mapping("start", m.get("start", "clamped"), base),
            end=end_from_mapping("end", m.get("end", "free"), base),
            loads=loads,
            simulation=_settings(Simulation, "simulation", m.get("simulation")),
            statics=_settings(Statics, "statics", m.get("statics")),
            analysis=_settings(Analysis, "analysis", m.get("analysis")),
            base=base,
            zones=zones,
            points=tuple(points),
        )

    def with_overrides(self, overrides: Mapping[str, Any]) -> Problem:
        """A new problem with dotted-path values replaced (aliases allowed), all checked.

        Keys are applied in order: dotted paths (``"material.tau"``, ``"loads.0.vector"``),
        the short :data:`ALIASES`, or a top-level table (``"material"``, ``"loads"``). A
        value may be a whole table (dict) or array of tables (list of dicts); the index
        one past an array's last entry appends a whole entry (``{"loads.1": {"kind":
        "force", "vector": [0, 0, 1.0]}}``). The result is validated exactly as a problem
        file would be (:meth:`from_mapping`); the caller's values are not modified.
        """
        if not overrides:
            return self
        if isinstance(self.rod.geometry, Curve) and getattr(self.rod.geometry, "_source",
                                                           None) is None:
            raise ParameterError("rod.geometry", "curve", "a TOML-expressible geometry for "
                                 "overrides (a Python callable)")
        base = self.__dict__.get("_mapping")
        if base is None:                  # a study applies thousands of overrides to one
            base = self.to_mapping()
            object.__setattr__(self, "_mapping", base)
        m = copy.deepcopy(base)
        used: dict[str, str] = {}
        for key, value in overrides.items():
            used[apply_override(m, key, value)] = key
        try:
            return Problem.from_mapping(m, base=self.base, name=self.name,
                                        points=self.points)
        except ParameterError as exc:   # name the value as the caller wrote it
            if exc.name in used and used[exc.name] != exc.name:
                raise ParameterError(f"{used[exc.name]} ({exc.name})", exc.value,
                                     exc.allowed, exc.where) from None
            raise


BESIDE_COMPOSITE = ("no [material] beside [section] kind = 'composite': a composite section "
                    "takes its materials from its regions (section.regions[i].material "
                    "names a [materials.NAME] table); [material] is the material of a "
                    "homogeneous rod")


def section_and_material(m: Mapping[str, Any]) -> tuple[Section, Material | None]:
    """The section and material of a problem (or section) file's table: ``[section]``
    with ``[material]`` (homogeneous) or with ``[materials.NAME]`` (composite; then no
    ``[material]``), and the damping route ``section.damping`` (or the older
    ``material.damping``; both given must agree), kept with a Kelvin-Voigt material or a
    composite section."""
    sec_m = dict(C.table("section", m["section"] if m.get("section") is not None else {}))
    has_material = m.get("material") is not None
    if sec_m.get("kind") == "composite" and has_material:
        raise ParameterError("material", m["material"], BESIDE_COMPOSITE)
    if "materials" in m and sec_m.get("kind") != "composite":
        raise ParameterError("materials", m["materials"], "[materials.NAME] tables only "
                             "with [section] kind = 'composite' (whose regions name them); "
                             "a homogeneous rod takes its material from [material]")
    mat_m = dict(C.table("material", m["material"] if has_material else {}))
    new, old = sec_m.get("damping"), mat_m.get("damping")
    if new is not None:
        C.choice("section.damping", new, DAMPING_ROUTES)
    if old is not None:
        C.choice("material.damping", old, DAMPING_ROUTES)
    if new is not None and old is not None and new != old:
        raise ParameterError("section.damping", new, f"the route of material.damping = "
                             f"{old!r} (the key's earlier place, still read), or give one "
                             "of them only")
    route = new if new is not None else old
    section = section_from_mapping(sec_m, m.get("materials"))
    if isinstance(section, Composite):
        return section, None
    if route is not None:
        if mat_m.get("model", "kelvin_voigt") == "kelvin_voigt":
            mat_m["damping"] = route
        elif route != "consistent":
            raise ParameterError("section.damping" if new is not None else "material.damping",
                                 route, "'consistent' for a generalized Maxwell material "
                                 "(the naive route is a Kelvin-Voigt notion)")
    material = material_from_mapping(mat_m)
    if (isinstance(section, GivenStiffness) and section.viscosity_matrix is not None
            and route == "naive"):
        raise ParameterError("section.damping" if new is not None else "material.damping",
                             route, "'consistent' (or absent) beside section.viscosity_matrix: "
                             "the route derives a rod viscosity from a material; the given "
                             "matrix is the rod's viscosity already")
    if (isinstance(section, GivenStiffness) and section.viscosity_matrix is not None
            and (getattr(material, "tau_S", 0.0) or getattr(material, "tau_B", 0.0))):
        # the given viscosity is the rod's whole viscosity: a retardation time of the
        # material beside it would be reported (tau_E) but act nowhere
        key = next((k for k in ("tau", "tau_S", "tau_B", "eta", "zeta")
                    if mat_m.get(k)), "tau_S")
        raise ParameterError(f"material.{key}", mat_m[key] if key in mat_m else "given",
                             "0 (or absent) beside section.viscosity_matrix: the section's "
                             "6x6 viscosity is the rod's whole viscosity; give one of them")
    return section, material


def _time_peak(tf: Any) -> float:
    """The largest absolute value a time function takes (ramps, steps, releases: 1)."""
    kind = getattr(tf, "kind", "constant")
    with np.errstate(over="ignore"):
        if kind == "constant":
            return abs(float(tf.value))
        if kind == "harmonic":
            return abs(float(tf.offset)) + abs(float(tf.amplitude))
        if kind == "table":
            return max((abs(float(v)) for _, v in tf.points), default=0.0)
    return 1.0


def _settings(cls, path: str, m: Any):
    m = dict(C.table(path, m if m is not None else {}))
    names = tuple(cls.__dataclass_fields__)
    C.no_unknown_keys(path, m, names)
    return cls(**m)


#: short names of the command line and of sweeps -> dotted paths
ALIASES: dict[str, str] = {
    "tau": "material.tau", "tau_S": "material.tau_S", "tau_B": "material.tau_B",
    "youngs_modulus": "material.youngs_modulus", "E": "material.youngs_modulus",
    "poisson_ratio": "material.poisson_ratio", "nu": "material.poisson_ratio",
    "density": "material.density", "damping": "section.damping",
    "n_elements": "rod.elements", "elements": "rod.elements", "length": "rod.length",
    "width": "section.width", "height": "section.height", "radius": "section.radius",
    "t_end": "simulation.t_end", "rtol": "simulation.rtol", "atol": "simulation.atol",
    "output_step": "simulation.output_step", "max_order": "simulation.max_order",
    "error_control": "simulation.error_control",
    "min_step": "simulation.min_step", "load_steps": "statics.load_steps",
    "shear_correction": "section.shear_correction",
    "tip_force": "tip_force",
}


def resolve_alias(key: str) -> str:
    """The dotted path of a key or alias (unknown single words are errors); a top-level
    table or key of a problem file (``material``, ``loads``, ``name``, ...) is its own
    path."""
    if key in ALIASES:
        return ALIASES[key]
    if "." in key or key in TOP_KEYS:
        return key
    raise ParameterError(key, None, "a dotted path (e.g. material.tau), a top-level key ("
                         + ", ".join(TOP_KEYS) + ") or one of: " + ", ".join(sorted(ALIASES)))


def _list_index(path: str, part: str, size: int, append: bool) -> int:
    """The index ``part`` of an array of ``size`` entries: 0 ... size - 1, or ``size``
    (append a new entry) when the whole entry is given (``append``)."""
    top = size if append else size - 1
    if part.isdigit() and int(part) <= top:
        return int(part)
    allowed = f"an index 0 ... {top}" if top >= 0 else "no index: the array is empty"
    if append:
        allowed += f" ({size} appends a new entry)"
    else:
        allowed += (f"; to append an entry, set {path.rsplit('.', 1)[0]}.{size} to a whole "
                    "table (e.g. --set loads.1={kind = \"force\", vector = [0, 0, 1]})")
    raise ParameterError(path, part, allowed)


def apply_override(m: dict[str, Any], key: str, value: Any) -> str:
    """Set ``key`` (dotted path or alias) in the problem mapping ``m`` in place.

    A path through an array (``loads.0.vector``) names an entry by its index; the whole
    entry at index ``len(array)`` appends one (``loads.1 = {kind = "force", ...}`` to a
    problem with one load). Values are deep-copied (the caller's dicts stay untouched).
    Returns the dotted path the value went to (``tip_force``: that load's vector), the
    name a rejected value is reported under.
    """
    value = copy.deepcopy(value)
    path = resolve_alias(key)
    if path == "tip_force":
        return _set_tip_force(m, value)
    parts = path.split(".")
    if not all(parts):
        raise ParameterError(path, value, "a dotted path without empty parts "
                             "(e.g. loads.0.vector)")
    if path in ("material.damping", "section.damping"):
        # one place for the route: the key set replaces the other (the older one is read)
        other = m.get("section" if path == "material.damping" else "material")
        if isinstance(other, dict):
            other.pop("damping", None)
    mat: Any = None
    if parts[0] == "material" and len(parts) == 2:  # one way of giving the viscosity
        mat = m.setdefault("material", {})
    elif (parts[0] == "materials" and len(parts) == 3
          and isinstance(m.get("materials"), dict)
          and isinstance(m["materials"].get(parts[1]), dict)):
        mat = m["materials"][parts[1]]       # a named material of a composite section
    if isinstance(mat, dict):
        if parts[-1] == "tau":
            for k in ("tau_S", "tau_B", "eta", "zeta"):
                mat.pop(k, None)
        elif parts[-1] in ("tau_S", "tau_B"):
            if "tau" in mat:
                t = mat.pop("tau")
                mat.setdefault("tau_S", t)
                mat.setdefault("tau_B", t)
            mat.pop("eta", None)
            mat.pop("zeta", None)
        elif parts[-1] in ("eta", "zeta"):  # the viscosities replace the retardation times
            _times_to_viscosities(mat, keep=parts[-1])
    if (parts[:2] == ["material", "branches"] and len(parts) == 4
            and isinstance(m.get("material", {}).get("branches"), list)):
        branches = m["material"]["branches"]
        if parts[2].isdigit() and int(parts[2]) < len(branches):
            _branch_spring_as(branches[int(parts[2])], parts[3])
    node: Any = m
    for i, part in enumerate(parts[:-1]):
        here = ".".join(parts[:i + 1])
        if isinstance(node, list):
            node = node[_list_index(here, part, len(node), append=False)]
        else:
            if part not in node or not isinstance(node[part], (dict, list)):
                # an index next (zones.0 on a problem without zones): an array of tables,
                # so the index appends its first entry as in a file's [[zones]]
                node[part] = [] if parts[i + 1].isdigit() else {}
            node = node[part]
    last = parts[-1]
    if parts[0] == "loads" and len(parts) == 3 and isinstance(node, dict):
        # a point load is placed by `at` or by `s`: the one given replaces the other
        node.pop({"s": "at", "at": "s"}.get(last, ""), None)
    if isinstance(node, list):
        k = _list_index(path, last, len(node), append=True)
        if k == len(node):
            node.append(value)
        else:
            node[k] = value
    else:
        node[last] = value
    return path


def _branch_spring_as(branch: Any, key: str) -> None:
    """Before one spring constant of a Maxwell branch is set: its spring is rewritten in
    the pair that key belongs to (E, nu or G, K: eq. of isotropic elasticity), so the
    other constant keeps its meaning and the branch is given one way."""
    if not isinstance(branch, dict):
        return
    try:
        if key in ("youngs_modulus", "poisson_ratio") and "shear_modulus" in branch:
            G, K = float(branch.pop("shear_modulus")), float(branch.pop("bulk_modulus", 0.0))
            branch.setdefault("youngs_modulus", 9 * K * G / (3 * K + G) if 3 * K + G else 0.0)
            branch.setdefault("poisson_ratio", (3 * K - 2 * G) / (2 * (3 * K + G))
                              if 3 * K + G else 0.0)
        elif key in ("shear_modulus", "bulk_modulus") and "youngs_modulus" in branch:
            E, nu = float(branch.pop("youngs_modulus")), float(branch.pop("poisson_ratio", 0.3))
            branch.setdefault("shear_modulus", E / (2 * (1 + nu)))
            branch.setdefault("bulk_modulus", E / (3 * (1 - 2 * nu)))
    except (TypeError, ValueError, ZeroDivisionError):
        return                               # the parser names the bad value


def _times_to_viscosities(mat: dict[str, Any], keep: str) -> None:
    """Before ``material.eta`` or ``.zeta`` is set: the retardation times of the mapping
    become viscosities (eta = G tau_S, zeta = K tau_B), so the one not set keeps its
    value and the material is given one way (the parser refuses a mix)."""
    if "tau" in mat:
        t = mat.pop("tau")
        mat.setdefault("tau_S", t)
        mat.setdefault("tau_B", t)
    tS, tB = mat.pop("tau_S", None), mat.pop("tau_B", None)
    E, nu = mat.get("youngs_modulus", 1.0e6), mat.get("poisson_ratio", 0.3)
    try:
        G = float(E) / (2 * (1 + float(nu)))
        K = math.inf if float(nu) >= 0.5 else float(E) / (3 * (1 - 2 * float(nu)))
    except (TypeError, ValueError, ZeroDivisionError):
        return                               # the parser names the bad E or nu
    if keep == "eta" and tB is not None and "zeta" not in mat:
        mat["zeta"] = 0.0 if math.isinf(K) else K * float(tB)
    if keep == "zeta" and tS is not None and "eta" not in mat:
        mat["eta"] = G * float(tS)


def _set_tip_force(m: dict[str, Any], value: Any) -> str:
    """tip_force F: the first point force at the s = L end gets magnitude |F| along its
    direction (the sign of F flips it). Returns the path of that load's vector."""
    F = C.number("tip_force", value)
    for k, ld in enumerate(m.get("loads", [])):
        if ld.get("kind", "force") == "force" and ld.get("at", "end") == "end" and "s" not in ld:
            v = np.array(ld.get("vector", [0.0, 0.0, 0.0]), dtype=float)
            nv = float(np.linalg.norm(v))
            if nv == 0:
                raise ParameterError("tip_force", value, "a problem whose end force has a "
                                     "direction (its vector is zero)")
            ld["vector"] = list(F * v / nv)
            return f"loads.{k}.vector"
    raise ParameterError("tip_force", value, "a problem with a point force at the end "
                         "(use --set loads.K.vector=... otherwise)")


def is_given_stiffness(p: Problem) -> bool:
    return isinstance(p.section, GivenStiffness)

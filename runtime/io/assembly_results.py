"""Results folders of an assembly of rods (issue 31): what `kvrod simulate` and `kvrod
static` write for a problem with ``[rods.NAME]`` tables.

series.npz (a run): ``t`` (n,), per rod ``NAME/start`` and ``NAME/end`` (3, n) end
positions (m) and ``NAME/centreline`` (m, 3, N+1) node positions at ``centreline_t``,
``NAME/reference`` (3, N+1), per joint ``joint{k}/force`` and ``joint{k}/moment`` (3, n; N,
N m: what the joint exerts on the rod of its first point, spatial, about that point), per
body (file order) ``body{k}/centreline`` (m, 3) its mass centre at ``centreline_t``, the
energies ``kinetic``, ``elastic``, ``dissipated``, ``external_work`` (J) and
``energy_balance_rel``, ``peaks_t``/``peaks_x``, ``y_static``, ``y_last``, per
obstacle k the values of ``runtime.model.contact.obstacle_series`` summed over the rods:
``obstacle{k}_force``, ``_moment`` (3, n), ``_energy``, ``_dissipation``,
``_friction_dissipation``, ``_power``, ``_gap_min``, ``_segments`` (n,), as a single rod's;
with ``contact.self`` the pairs between and within the rods: ``self_contact_energy`` (J),
``_dissipation``, ``_friction_dissipation`` (W), ``_gap_min`` (m; inf: no pair),
``_pairs`` and ``_force`` (N: the sum of the pairs' force magnitudes), (n,).
static.npz (statics): ``y``, per rod ``NAME/positions`` (3, N+1), ``NAME/frames``
(N, 3, 3), ``NAME/reference`` (3, N+1), per joint ``joint{k}/force``, ``joint{k}/moment``
(3,), per obstacle ``obstacle{k}_force``, ``obstacle{k}_moment`` (3,; N, N m about its
point, on the rods). summary.json has, at its top level, ``"joints"``: a list in file
order with each joint's ``force`` and ``moment`` (statics: 3-vectors; a run: the final
value and the largest with its time, like the supports' reactions), ``"bodies"``: each body's
mass-centre position and frame, and on obstacles ``"obstacles"`` (each one's force,
moment and smallest gap, as a single rod's).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from runtime.io.results import jsonable, write_json, write_npz, write_problem


def is_assembly(problem) -> bool:
    """A problem of several rods (``[rods.NAME]``)."""
    return hasattr(problem, "joints") and hasattr(problem, "rods")


def write_assembly_run(out_dir: Path, res, extra: dict | None = None) -> dict:
    """summary.json, series.npz and problem.toml of an
    :class:`~runtime.simulate.assembly.AssemblyResult` (see the module docstring)."""
    out_dir = Path(out_dir)
    summary = res.summary()
    if extra:
        summary.update(extra)
    arrays: dict[str, np.ndarray] = {}
    model = res.model
    for key, v in res.ends.items():
        arrays[key] = v
    for name, v in res.centreline.items():
        arrays[f"{name}/centreline"] = v
    for k, v in enumerate(res.body_centreline):
        arrays[f"body{k}/centreline"] = v
    if model is not None:
        for k, name in enumerate(model.names):
            rod = model.rods[k]
            arrays[f"{name}/reference"] = rod.positions(rod.reference)
    for k, j in enumerate(res.joint_series() if res.t.size else []):
        arrays[f"joint{k}/force"] = j["force"]
        arrays[f"joint{k}/moment"] = j["moment"]
    for k, o in enumerate(res.obstacle_series()):
        arrays.update({f"obstacle{k}_{what}": v for what, v in o.items()})
    for what, v in res.self_contact_series().items():
        arrays[f"self_contact_{what}"] = v
    audit = res.audit()
    write_npz(out_dir / "series.npz", t=res.t, kinetic=res.kinetic, elastic=res.elastic,
              dissipated=res.dissipated, external_work=res.external_work,
              energy_balance_rel=audit.relative, peaks_t=res.peaks_t, peaks_x=res.peaks_x,
              centreline_t=res.centreline_t,
              y_static=res.static.y if res.static is not None else np.zeros(0),
              y_last=res.y_last if res.y_last is not None else np.zeros(0), **arrays)
    write_problem(out_dir / "problem.toml", summary["parameters"])
    write_json(out_dir / "summary.json", summary)
    return summary


def static_joint_values(amap, y: np.ndarray) -> list[dict[str, list[float]]]:
    """Each joint's force and moment on the rod of its first point at the equilibrium y."""
    from runtime.simulate.assembly import joint_forces

    model = amap.model
    with model.statics():
        e = model.energy_values(0.0, y)
    extras = e[5:, None]
    return [{"force": [float(v) for v in j["force"][:, 0]],
             "moment": [float(v) for v in j["moment"][:, 0]]}
            for j in joint_forces(amap, extras)]


def static_obstacle_values(amap, y: np.ndarray, obstacles) -> list[dict]:
    """Per obstacle (file order; ``obstacles`` the problem's) at the equilibrium y: the
    force and moment it exerts on the rods, the smallest gap and the segments in reach
    (:func:`runtime.simulate.simulate.static_obstacle_summary`)."""
    from runtime.model.contact import N_VALUES
    from runtime.simulate.simulate import static_obstacle_summary

    model = amap.model
    if not model.n_obstacles:
        return []
    with model.statics():
        e = model.energy_values(0.0, y)
    first = model.extras_layout()["obstacle:0"].start
    return static_obstacle_summary(obstacles, e[first:first + N_VALUES * model.n_obstacles])


def static_assembly_and_write(problem, out: Path, overwrite: bool = False,
                              sensitivities: list[str] | None = None) -> tuple:
    """The static equilibrium of an assembly under its loads at t = 0- into results folder
    ``out`` (checked and locked like a single rod's; see the module docstring). Returns
    (summary, amap, y); a failed solve keeps its last converged state (status "failed")
    and writes no sensitivities. ``sensitivities``: parameter names (validated before
    anything is written) whose static sensitivities go to ``sensitivities.npz``
    (:func:`runtime.simulate.assembly_sensitivity.static_assembly_channels`)."""
    from runtime.io.folder import RUN_FILES, results_folder
    from runtime.model import build
    from runtime.model.system_statics import SystemStatics
    from runtime.problem.assemble_system import build_system
    from runtime.simulate.assembly import body_state, static_ends, static_equilibrium
    from runtime.solvers.statics import StaticSolveError

    sens_run = None
    if sensitivities is not None:
        from runtime.problem.parameters import resolve_parameters
        from runtime.simulate.assembly_sensitivity import AssemblySensitivityRun

        sens_run = AssemblySensitivityRun(problem, resolve_parameters(problem, sensitivities))
    build.require_generated()
    wall0 = time.perf_counter()
    amap = build_system(problem)
    model = amap.model
    with model.statics():                     # an ill-posed problem: before the folder
        SystemStatics(model).hold_rigid_motions(model.initial_state())
    if sens_run is not None:
        sens_run.prepare(model)
    with results_folder(out, "static", markers=("summary.json",), overwrite=overwrite,
                        names=RUN_FILES):
        params = jsonable(problem.to_mapping())
        try:
            st = static_equilibrium(problem, amap)
            status, message, y, its, per = ("finished", "ok", st.y, st.iterations,
                                            st.per_step)
        except StaticSolveError as exc:
            status, message, y, its, per = ("failed", f"static solve failed: {exc}", exc.y,
                                            sum(exc.iterations), list(exc.iterations))
        joints = static_joint_values(amap, y)
        obstacles = static_obstacle_values(amap, y, problem.obstacles)
        summary = {"status": status, "message": message, "problem": problem.name,
                   "parameters": params,
                   "assembly": {"rods": list(problem.rods), "joints": len(problem.joints),
                                "bodies": len(problem.bodies)},
                   "static": {"ends": static_ends(amap, y), "newton_iterations": int(its),
                              "newton_iterations_per_load_step": per,
                              "wall_time_s": time.perf_counter() - wall0},
                   "joints": [{"index": k, "kind": jt.kind,
                               "between": [jt.first.label, "ground" if jt.second is None
                                           else jt.second.label], **joints[k]}
                              for k, jt in enumerate(problem.joints)],
                   "bodies": {b.name: body_state(model, body, y)
                              for b, body in zip(problem.bodies, model.bodies, strict=True)},
                   **({"obstacles": obstacles} if obstacles else {}),
                   "backend": "c"}
        arrays: dict[str, np.ndarray] = {"y": y}
        for k, name in enumerate(model.names):
            rod = model.rods[k]
            ys = model.rod_state(k, y)
            arrays[f"{name}/positions"] = rod.positions(ys)
            arrays[f"{name}/frames"] = rod.frames(ys)
            arrays[f"{name}/reference"] = rod.positions(rod.reference)
        for k, j in enumerate(joints):
            arrays[f"joint{k}/force"] = np.array(j["force"])
            arrays[f"joint{k}/moment"] = np.array(j["moment"])
        for k, o in enumerate(obstacles):
            arrays[f"obstacle{k}_force"] = np.array(o["force"])
            arrays[f"obstacle{k}_moment"] = np.array(o["moment"])
        write_npz(out / "static.npz", **arrays)
        if sens_run is not None and status == "finished":
            from runtime.io.runs import write_sensitivities
            from runtime.simulate.assembly_sensitivity import static_assembly_channels

            sens = static_assembly_channels(amap, y, sens_run)
            write_sensitivities(out, sens)
            summary["sensitivities"] = sens.summary()
        write_problem(out / "problem.toml", params)
        write_json(out / "summary.json", summary)
    return summary, amap, y

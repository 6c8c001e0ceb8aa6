"""Pictures of an assembly of rods (issue 31): every rod and body in one figure.

Drawn from the results folders (:mod:`runtime.io.assembly_results`,
:mod:`runtime.io.assembly_modes`) by ``kvrod simulate ASSEMBLY --plots`` and ``kvrod
plot DIR``, with the helpers of :mod:`runtime.io.shapes` (equal axes in 3-D, the
projection on the plane of largest spread, blitted animation frames):

* a static result: ``shape.png`` (:func:`figure_assembly_static`: each rod's equilibrium
  in its colour, the references dashed grey, the bodies as black dots);
* a run: ``ends.png`` (each rod's end displacements), ``energy.png``
  (:func:`runtime.io.plots.figure_energy`), ``joint_forces.png`` (each joint's force and
  moment magnitudes over time), ``centreline.png`` (every rod at a few frame times,
  coloured by time; bodies as dots), ``damping_ratio.png`` (with two maxima or more);
  ``--animate``: ``centreline.gif``/``.mp4`` (:func:`animate_assembly`);
* modes: ``mode_shapes_3d.png`` (:func:`figure_assembly_mode_shapes`).

Arrays: node positions (3, N+1) in m, frames (m, 3, N+1), body positions (3,) or (m, 3).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from runtime.io.figures import pyplot, save
from runtime.io.shapes import (
    GREY,
    MAX_ANIMATION_FRAMES,
    MAX_MODES,
    MODE_DISPLACEMENT,
    MODE_ROTATION,
    RUN_SNAPSHOTS,
    animation_unavailable,
    equal_axes_3d,
    line3,
    mode_amplitude,
    projection_axes,
    render_frames,
    snapshot_indices,
    two_views,
    write_gif,
    write_mp4,
)

BODY_STYLE = {"marker": "o", "color": "k", "ms": 6, "ls": "none"}


def _points(*groups) -> np.ndarray:
    """Every point (3, n) of arrays (3, k) or (m, 3, k) and body positions (3,) or (m, 3)."""
    cols = []
    for g in groups:
        for a in g:
            a = np.asarray(a, dtype=float)
            if a.ndim == 1:
                cols.append(a[:, None])
            elif a.ndim == 2 and a.shape[0] == 3:
                cols.append(a)
            elif a.ndim == 2:                        # (m, 3) body positions over time
                cols.append(a.T)
            else:                                    # (m, 3, k) frames
                cols.append(np.hstack(list(a)))
    return np.hstack(cols) if cols else np.zeros((3, 0))


def _label_rods(ax2, a: int, b: int, shapes: dict[str, np.ndarray]) -> None:
    """Each rod's name beside its middle node on the projection."""
    for name, r in shapes.items():
        mid = r[:, r.shape[1] // 2]
        ax2.annotate(name, (mid[a], mid[b]), fontsize=7, color="0.25",
                     xytext=(3, 3), textcoords="offset points")


# --------------------------------------------------------------------------------------
# static equilibrium
# --------------------------------------------------------------------------------------

def figure_assembly_static(positions: dict[str, np.ndarray],
                           references: dict[str, np.ndarray],
                           bodies: Sequence[tuple[str, np.ndarray]] = (), title: str = ""):
    """Every rod's static equilibrium (solid, its own colour, nodes marked) and its
    stress-free reference (dashed grey), the bodies' mass centres (black dots), in 3-D
    and projected."""
    fig, ax3, ax2 = two_views()
    pts = _points(positions.values(), references.values(), [p for _, p in bodies])
    for k, (name, r) in enumerate(positions.items()):
        ref = references.get(name)
        if ref is not None:
            line3(ax3, ref, "--", color=GREY, lw=1.0)
        line3(ax3, r, "-", color=f"C{k}", lw=1.6, label=name)
    for _, p in bodies:
        ax3.plot([p[0]], [p[1]], [p[2]], **BODY_STYLE)
    equal_axes_3d(ax3, pts)
    a, b = projection_axes(ax2, pts)
    for k, (name, r) in enumerate(positions.items()):
        ref = references.get(name)
        if ref is not None:
            ax2.plot(ref[a], ref[b], "--", color=GREY, lw=1.0,
                     label="reference" if k == 0 else None)
        ax2.plot(r[a], r[b], ".-" if r.shape[1] <= 61 else "-", color=f"C{k}", lw=1.6,
                 ms=3, label=name)
    for j, (_, p) in enumerate(bodies):
        ax2.plot([p[a]], [p[b]], **BODY_STYLE, label="bodies" if j == 0 else None)
    ax2.legend(fontsize=8, loc="best")
    fig.suptitle(title or "static equilibrium", fontsize=10)
    fig.tight_layout()
    return fig


def plot_assembly_static(positions: dict[str, np.ndarray], references: dict[str, np.ndarray],
                         path: Path, bodies: Sequence[tuple[str, np.ndarray]] = (),
                         title: str = "") -> Path:
    """:func:`figure_assembly_static` as PNG."""
    return save(figure_assembly_static(positions, references, bodies, title), path, dpi=110)


# --------------------------------------------------------------------------------------
# a run read back
# --------------------------------------------------------------------------------------

@dataclass
class AssemblyRun:
    """An assembly's run read back from its folder (summary.json, series.npz): what the
    plots use. ``ends``: {rod: {"start": (3, n), "end": (3, n)}}; ``centreline``: {rod:
    (m, 3, N+1)}; ``reference``: {rod: (3, N+1)}; ``joints``: [(label, force (3, n),
    moment (3, n))]; ``bodies``: [(name, mass centre (m, 3) at ``centreline_t``)]."""

    name: str
    rods: list[str]
    t: np.ndarray
    kinetic: np.ndarray
    elastic: np.ndarray
    dissipated: np.ndarray
    external_work: np.ndarray
    energy_balance_rel: np.ndarray
    peaks_t: np.ndarray
    peaks_x: np.ndarray
    centreline_t: np.ndarray
    ends: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    centreline: dict[str, np.ndarray] = field(default_factory=dict)
    reference: dict[str, np.ndarray] = field(default_factory=dict)
    joints: list[tuple[str, np.ndarray, np.ndarray]] = field(default_factory=list)
    bodies: list[tuple[str, np.ndarray]] = field(default_factory=list)

    @property
    def frames(self) -> int:
        """The number of centreline frames every rod has (0: none)."""
        return min((v.shape[0] for v in self.centreline.values()), default=0)


def _summary(folder: Path) -> dict:
    path = Path(folder) / "summary.json"
    try:
        data = json.loads(path.read_text())
        if isinstance(data, dict) and isinstance(data["assembly"]["rods"], list):
            return data
    except (OSError, ValueError, KeyError, TypeError):
        pass
    raise ValueError(f"{path} is not the summary of an assembly's result (no readable "
                     "\"assembly\" entry); run the problem again (DIR/problem.toml)")


def _damaged(path: Path, why: str) -> ValueError:
    return ValueError(f"{path} is damaged ({why}); run the problem again (DIR/problem.toml) "
                      "to rewrite it")


def _body_names(summary: dict) -> list[str]:
    bodies = summary.get("parameters", {}).get("bodies", [])
    return [str(b.get("name", f"body{k}")) if isinstance(b, dict) else f"body{k}"
            for k, b in enumerate(bodies)]


def _joint_label(j: dict, k: int) -> str:
    between = " - ".join(str(x) for x in j.get("between", []))
    return f"joint {k} ({j.get('kind', '')} {between})".replace(" ()", "")


def load_assembly_run(folder: Path) -> AssemblyRun:
    """Read an assembly's run folder (module docstring); ValueError naming the file when
    it is not one or is damaged."""
    import zipfile

    folder = Path(folder)
    s = _summary(folder)
    rods = [str(r) for r in s["assembly"]["rods"]]
    path = folder / "series.npz"
    scalars = ("t", "kinetic", "elastic", "dissipated", "external_work",
               "energy_balance_rel", "peaks_t", "peaks_x", "centreline_t")
    try:
        with np.load(path, allow_pickle=False) as f:
            files = set(f.files)
            get = {k: np.asarray(f[k], dtype=float) if k in files else np.zeros(0)
                   for k in scalars}
            ends = {r: {e: np.asarray(f[f"{r}/{e}"], dtype=float) for e in ("start", "end")}
                    for r in rods}
            centre = {r: np.asarray(f[f"{r}/centreline"], dtype=float) for r in rods
                      if f"{r}/centreline" in files}
            refs = {r: np.asarray(f[f"{r}/reference"], dtype=float) for r in rods
                    if f"{r}/reference" in files}
            joints = [(_joint_label(j, k), np.asarray(f[f"joint{k}/force"], dtype=float),
                       np.asarray(f[f"joint{k}/moment"], dtype=float))
                      for k, j in enumerate(s.get("joints", []))
                      if f"joint{k}/force" in files]
            bodies = [(n, np.asarray(f[f"body{k}/centreline"], dtype=float))
                      for k, n in enumerate(_body_names(s)) if f"body{k}/centreline" in files]
    except KeyError as exc:
        raise _damaged(path, f"no array {exc}") from None
    except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise _damaged(path, f"{type(exc).__name__}: {' '.join(str(exc).split())[:120]}"
                       ) from None
    nt = get["t"].shape
    bad = [f"{r}/{e}" for r in rods for e in ("start", "end") if ends[r][e].shape != (3, *nt)]
    bad += [f"joint{k}" for k, (_, f_, m_) in enumerate(joints)
            if f_.shape != (3, *nt) or m_.shape != (3, *nt)]
    if get["t"].ndim != 1 or bad:
        raise _damaged(path, f"arrays {', '.join(bad) or 't'} do not match t of shape {nt}")
    return AssemblyRun(str(s.get("problem", folder.name)), rods, ends=ends, centreline=centre,
                       reference=refs, joints=joints, bodies=bodies, **get)


# --------------------------------------------------------------------------------------
# a run's figures
# --------------------------------------------------------------------------------------

#: an end's displacement component is drawn when it exceeds this fraction of the largest
#: of any end (rounding in a held end, or a motion out of the plane of a plane one, is not)
ENDS_RTOL = 1e-6


def figure_assembly_ends(run: AssemblyRun):
    """Each rod's end displacements from t = 0 (one panel per rod; x, y, z of s = L solid,
    of s = 0 dashed), components above :data:`ENDS_RTOL` of the largest."""
    plt = pyplot()
    n = max(len(run.rods), 1)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.2 + 2.2 * n), sharex=True, squeeze=False)
    disp = {(r, e): a - a[:, :1] for r, ends in run.ends.items() for e, a in ends.items()
            if a.size}
    big = max((float(np.nanmax(np.abs(d))) for d in disp.values() if d.size), default=0.0)
    for ax, name in zip(axes[:, 0], run.rods, strict=False):
        for end, style in (("end", "-"), ("start", "--")):
            d = disp.get((name, end))
            if d is None:
                continue
            for c, comp in enumerate("xyz"):
                if big > 0 and np.nanmax(np.abs(d[c])) > ENDS_RTOL * big:
                    ax.plot(run.t, d[c], style, color=f"C{c}", lw=1.0,
                            label=f"{comp} ({name}.{end})")
        ax.axhline(0, color="0.7", lw=0.5)
        ax.set_ylabel(f"{name} [m]")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      frameon=False)
        else:
            ax.text(0.02, 0.5, "ends at rest", transform=ax.transAxes, fontsize=8)
    axes[-1, 0].set_xlabel("time t [s]")
    fig.suptitle(f"{run.name}: end displacements from t = 0", fontsize=10)
    return fig


def figure_joint_forces(run: AssemblyRun):
    """Each joint's force and moment magnitude over time (on the rod of its first point)."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for k, (label, f, m) in enumerate(run.joints):
        a1.plot(run.t, np.linalg.norm(f, axis=0), color=f"C{k % 10}", lw=1.0, label=label)
        a2.plot(run.t, np.linalg.norm(m, axis=0), color=f"C{k % 10}", lw=1.0)
    a1.set_ylabel("|force| [N]")
    a2.set_ylabel("|moment| [N m]")
    a2.set_xlabel("time t [s]")
    if run.joints:
        a1.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.suptitle(f"{run.name}: what each joint exerts on the rod of its first point",
                 fontsize=10)
    return fig


def figure_assembly_centreline(run: AssemblyRun, count: int = RUN_SNAPSHOTS):
    """Every rod at ``count`` frame times (colour: time, colour bar in s), the bodies'
    mass centres (dots, same colours) and the stress-free references (dashed grey), in
    3-D and projected."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    plt = pyplot()
    t = run.centreline_t
    m = run.frames
    idx = snapshot_indices(m, count)
    t0, t1 = float(t[0]), float(t[m - 1])
    norm = Normalize(t0, t1 if t1 > t0 else t0 + 1.0)
    cmap = plt.get_cmap("viridis")
    fig, ax3, ax2 = two_views(figsize=(11.5, 4.6))
    frames = {r: v[idx] for r, v in run.centreline.items()}
    bodies = [(n, c[idx]) for n, c in run.bodies if c.shape[0] >= m]
    pts = _points(run.reference.values(), frames.values(), [c for _, c in bodies])
    a, b = projection_axes(ax2, pts)
    for j, i in enumerate(idx):
        color = cmap(norm(t[i]))
        for f in frames.values():
            line3(ax3, f[j], "-", color=color, lw=1.3)
            ax2.plot(f[j][a], f[j][b], "-", color=color, lw=1.3)
        for _, c in bodies:
            ax3.plot([c[j, 0]], [c[j, 1]], [c[j, 2]], "o", color=color, ms=4)
            ax2.plot([c[j, a]], [c[j, b]], "o", color=color, ms=4)
    for k, ref in enumerate(run.reference.values()):
        line3(ax3, ref, "--", color=GREY, lw=1.0, zorder=5)
        ax2.plot(ref[a], ref[b], "--", color=GREY, lw=1.0, zorder=5,
                 label="reference" if k == 0 else None)
    _label_rods(ax2, a, b, run.reference or {r: f[0] for r, f in frames.items()})
    equal_axes_3d(ax3, pts)
    ax2.legend(fontsize=8, loc="best")
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax2, label="time t [s]",
                 shrink=0.85)
    fig.suptitle(f"{run.name}: every rod at {idx.size} of {m} frames, t = {t0:g} ... "
                 f"{t1:g} s" + ("; dots: bodies" if bodies else ""), fontsize=10)
    fig.tight_layout()
    return fig


def plot_assembly_run_folder(folder: Path) -> list[Path]:
    """ends.png, energy.png, joint_forces.png (with joints), centreline.png (with frames),
    damping_ratio.png (two maxima or more), contact.png (on obstacles) of an assembly's
    run folder."""
    from runtime.io.plots import (
        figure_energy,
        plot_contact_of_folder,
        plot_damping_vs_amplitude,
    )

    folder = Path(folder)
    run = load_assembly_run(folder)
    paths = [save(figure_assembly_ends(run), folder / "ends.png", dpi=120,
                  bbox_inches="tight"),
             save(figure_energy(run), folder / "energy.png", dpi=120, bbox_inches="tight")]
    if run.joints:
        paths.append(save(figure_joint_forces(run), folder / "joint_forces.png", dpi=120,
                          bbox_inches="tight"))
    if run.frames and run.centreline_t.size >= run.frames:
        paths.append(save(figure_assembly_centreline(run), folder / "centreline.png",
                          dpi=110))
    if run.peaks_x.size >= 2:
        paths.append(plot_damping_vs_amplitude([run], ["run"], [math.nan],
                                               folder / "damping_ratio.png"))
    contact = plot_contact_of_folder(folder, run.t, _summary(folder))
    return paths + ([contact] if contact is not None else [])


def plot_assembly_static_folder(folder: Path) -> Path:
    """shape.png of an assembly's static folder (static.npz, summary.json)."""
    folder = Path(folder)
    s = _summary(folder)
    rods = [str(r) for r in s["assembly"]["rods"]]
    path = folder / "static.npz"
    try:
        with np.load(path, allow_pickle=False) as f:
            pos = {r: np.asarray(f[f"{r}/positions"], dtype=float) for r in rods}
            ref = {r: np.asarray(f[f"{r}/reference"], dtype=float) for r in rods}
    except KeyError as exc:
        raise _damaged(path, f"no array {exc}") from None
    except (OSError, ValueError, EOFError) as exc:
        raise _damaged(path, type(exc).__name__) from None
    bodies = [(str(n), np.asarray(b["position"], dtype=float))
              for n, b in (s.get("bodies") or {}).items()]
    status = s.get("status", "")
    title = f"{s.get('problem', folder.name)}: static equilibrium" + (
        f" ({status}: last converged load step)" if status and status != "finished" else "")
    return plot_assembly_static(pos, ref, folder / "shape.png", bodies, title)


# --------------------------------------------------------------------------------------
# animation
# --------------------------------------------------------------------------------------

def animate_assembly(run: AssemblyRun, path: Path, fps: int = 20) -> Path:
    """Every rod's centreline frames as an animation (GIF or MP4 by ``path``'s suffix),
    each rod in its colour, the bodies as dots, the references dashed grey, 3-D view and
    projection with fixed, equal axes; at most :data:`~runtime.io.shapes.
    MAX_ANIMATION_FRAMES` frames. Raises ValueError naming the format when it cannot be
    written here."""
    from runtime.io.atomic import atomic_path

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    why = animation_unavailable(fmt)
    if why is not None:
        raise ValueError(why)
    m = run.frames
    idx = snapshot_indices(m, MAX_ANIMATION_FRAMES)
    frames = {r: v[idx] for r, v in run.centreline.items()}
    bodies = [c[idx] for _, c in run.bodies if c.shape[0] >= m]
    fig, ax3, ax2 = two_views(figsize=(9.0, 4.2))
    fig.set_dpi(80)
    pts = _points(run.reference.values(), frames.values(), bodies)
    a, b = projection_axes(ax2, pts)
    for k, ref in enumerate(run.reference.values()):
        line3(ax3, ref, "--", color=GREY, lw=1.0)
        ax2.plot(ref[a], ref[b], "--", color=GREY, lw=1.0,
                 label="reference" if k == 0 else None)
    lines3, lines2 = [], []
    for k, (name, f) in enumerate(frames.items()):
        lines3.append(line3(ax3, f[0], "-", color=f"C{k}", lw=1.6)[0])
        lines2.append(ax2.plot(f[0][a], f[0][b], "-", color=f"C{k}", lw=1.6, label=name)[0])
    dots3 = [ax3.plot([c[0, 0]], [c[0, 1]], [c[0, 2]], **BODY_STYLE)[0] for c in bodies]
    dots2 = [ax2.plot([c[0, a]], [c[0, b]], **BODY_STYLE)[0] for c in bodies]
    equal_axes_3d(ax3, pts)
    ax2.legend(fontsize=8, loc="upper right")
    ax2.update_datalim(np.column_stack([pts[a], pts[b]]))
    ax2.autoscale_view()
    fig.suptitle(run.name, fontsize=10)
    stamp = ax2.text(0.02, 0.97, "", transform=ax2.transAxes, va="top", fontsize=9)
    fig.tight_layout()
    t = run.centreline_t

    def update(i: int) -> None:
        for l3, l2, f in zip(lines3, lines2, frames.values(), strict=True):
            r = f[i]
            l3.set_data_3d(r[0], r[1], r[2])
            l2.set_data(r[a], r[b])
        for d3, d2, c in zip(dots3, dots2, bodies, strict=True):
            d3.set_data_3d([c[i, 0]], [c[i, 1]], [c[i, 2]])
            d2.set_data([c[i, a]], [c[i, b]])
        stamp.set_text(f"t = {float(t[idx[i]]):.4g} s")

    try:
        rendered = render_frames(fig, (*lines3, *lines2, *dots3, *dots2, stamp), update,
                                 idx.size)
        with atomic_path(path, suffix=path.suffix) as tmp:
            (write_gif if fmt == "gif" else write_mp4)(rendered, tmp, fps)
    finally:
        pyplot().close(fig)
    return path


# --------------------------------------------------------------------------------------
# mode shapes
# --------------------------------------------------------------------------------------

def _mode_title(m: dict) -> str:
    z = m.get("zeta")
    zs = "-" if z is None or (isinstance(z, float) and not math.isfinite(z)) else (
        f"{float(z):.3g}")
    shares = sorted((m.get("kinetic_energy_fractions") or {}).items(), key=lambda kv: -kv[1])
    where = ", ".join(f"{n} {100 * f:.0f}%" for n, f in shares[:2] if f >= 0.05)
    return (f"mode {m['index']}: f = {float(m.get('frequency_hz', 0.0)):.4g} Hz, "
            f"zeta = {zs}\n{where}")


def figure_assembly_mode_shapes(mf, max_modes: int = MAX_MODES):
    """The first ``max_modes`` mode shapes of an
    :class:`~runtime.io.assembly_modes.AssemblyModesFile`: every rod's equilibrium dashed
    grey, its shape at +/- one amplitude (solid / faint, the rod's colour), the bodies
    displaced (black dots). One amplitude per mode for all rods
    (:func:`~runtime.io.shapes.mode_amplitude` over every rod, against the assembly's
    size); equal axes, one cube for all modes."""
    plt = pyplot()
    k = min(len(mf.modes), max_modes)
    L = mf.size
    cols = min(4, max(k, 1))
    rows = max(1, math.ceil(k / cols))
    fig = plt.figure(figsize=(3.4 * cols, 3.5 * rows + 0.6))
    amps = []
    for j in range(k):
        d = np.hstack([mf.displacement[r][j] for r in mf.rods])
        rot = np.hstack([mf.rotation[r][j] for r in mf.rods])
        amps.append(mode_amplitude(d, rot, L))
    eq = list(mf.equilibrium.values())
    shown = [mf.equilibrium[r] + s * amps[j] * mf.displacement[r][j]
             for j in range(k) for r in mf.rods for s in (1.0, -1.0)]
    pts = _points(eq, shown, [p for _, p, _ in mf.bodies])
    for j in range(k):
        ax = fig.add_subplot(rows, cols, j + 1, projection="3d")
        a = amps[j]
        for c, r in enumerate(mf.rods):
            e, d = mf.equilibrium[r], mf.displacement[r][j]
            line3(ax, e, "--", color=GREY, lw=0.9)
            line3(ax, e - a * d, "-", color=f"C{c}", lw=0.8, alpha=0.35)
            line3(ax, e + a * d, ".-", color=f"C{c}", lw=1.4, ms=2)
        for _, p, dd in mf.bodies:
            q = p + a * dd[j]
            ax.plot([q[0]], [q[1]], [q[2]], **{**BODY_STYLE, "ms": 4})
        equal_axes_3d(ax, pts)
        ax.set_title(_mode_title(mf.modes[j]), fontsize=8)
    from matplotlib.lines import Line2D

    meta = mf.meta
    about = "static equilibrium under the loads" if meta.get("deformed") else "reference"
    more = f" (first {k} of {len(mf.modes)})" if len(mf.modes) > k else ""
    fig.suptitle(f"{meta.get('problem', 'modes')}: mode shapes{more} about the {about} "
                 f"(dashed), scaled to a largest displacement of {MODE_DISPLACEMENT:g} x "
                 f"{L:.3g} m or rotation of {MODE_ROTATION:g} rad", fontsize=9)
    handles = [Line2D([], [], color=f"C{c}", lw=1.4, label=r) for c, r in enumerate(mf.rods)]
    if mf.bodies:
        handles.append(Line2D([], [], **{**BODY_STYLE, "ms": 4}, label="bodies"))
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), fontsize=8,
               frameon=False)
    # fixed margins: tight_layout of 3-D axes costs a full draw (~0.1 s per axes)
    fig.subplots_adjust(left=0.02, right=0.96, bottom=0.35 / fig.get_figheight() + 0.02,
                        top=1 - 0.7 / fig.get_figheight(), wspace=0.15, hspace=0.3)
    return fig


def plot_assembly_mode_shapes(mf, path: Path, max_modes: int = MAX_MODES) -> Path:
    """:func:`figure_assembly_mode_shapes` as PNG."""
    return save(figure_assembly_mode_shapes(mf, max_modes), path, dpi=100)

"""Pictures of the rod itself: deformed centrelines in 3-D, with equal axes.

Each figure has a 3-D view (equal scales on x, y, z, so a shape is seen undistorted)
and beside it the projection on the coordinate plane in which the drawn shapes spread
most (equal aspect), with the reference shape (stress-free, or the equilibrium about
which modes are computed) dashed in grey:

* :func:`figure_static`: a static equilibrium and its reference (``static.npz``);
* :func:`figure_run_centreline`: a run's centreline at a few frame times coloured by
  time (``series.npz``: ``centreline``, ``centreline_t``);
* :func:`figure_mode_shapes_3d`: mode shapes about the equilibrium, scaled to a visible
  amplitude, with frequency, damping ratio and family in each title (``modes.json`` and
  ``modes.npz``, :mod:`runtime.io.modes`);
* :func:`animate_run`: the run's centreline frames as a GIF (Pillow, which matplotlib
  requires) or an MP4 (ffmpeg on PATH).

Arrays: node positions (3, N+1) in m; frames (m, 3, N+1).
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from runtime.io.figures import pyplot, save

#: how far a mode shape is drawn from its equilibrium: the largest node displacement
#: this fraction of the rod's length, or the largest segment rotation this angle (rad),
#: whichever is reached first
MODE_DISPLACEMENT = 0.2
MODE_ROTATION = 0.6
#: at most this many modes in one mode-shape figure, centrelines in a run's figure
MAX_MODES = 12
RUN_SNAPSHOTS = 8
#: at most this many frames in an animation (more are subsampled evenly)
MAX_ANIMATION_FRAMES = 400
GREY = "0.55"


def _cube(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and half-width of the smallest cube around ``points`` (3, k)."""
    pts = points[:, np.all(np.isfinite(points), axis=0)]
    if pts.size == 0:
        return np.zeros(3), 1.0
    lo, hi = pts.min(axis=1), pts.max(axis=1)
    half = float(np.max(hi - lo)) / 2
    return (lo + hi) / 2, half * 1.05 if half > 0 else 1.0


def equal_axes_3d(ax, points: np.ndarray) -> None:
    """Equal scales on x, y, z: a cube of data around ``points`` in a cubic box."""
    c, h = _cube(points)
    ax.set_xlim(c[0] - h, c[0] + h)
    ax.set_ylim(c[1] - h, c[1] + h)
    ax.set_zlim(c[2] - h, c[2] + h)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]", fontsize=8, labelpad=1)
    ax.set_ylabel("y [m]", fontsize=8, labelpad=1)
    ax.set_zlabel("z [m]", fontsize=8, labelpad=1)
    ax.tick_params(labelsize=6, pad=0)
    # few ticks: laying out the ticks of 3-D axes is most of their drawing time
    ax.locator_params(nbins=4)


def _plane(points: np.ndarray) -> tuple[int, int]:
    """The two coordinates (indices, ascending) in which ``points`` spread most."""
    pts = points[:, np.all(np.isfinite(points), axis=0)]
    spread = np.ptp(pts, axis=1) if pts.size else np.ones(3)
    a, b = sorted(np.argsort(-spread, kind="stable")[:2])
    return int(a), int(b)


def projection_axes(ax, points: np.ndarray) -> tuple[int, int]:
    """Equal-aspect 2-D axes on the plane of largest spread; returns its coordinates."""
    a, b = _plane(points)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    ax.grid(alpha=0.3)
    ax.set_title(f"projection on the {'xyz'[a]}{'xyz'[b]} plane", fontsize=9)
    return a, b


def two_views(figsize=(10.5, 4.6)):
    """A figure with a 3-D axes (left) and a 2-D axes for a projection (right)."""
    plt = pyplot()
    fig = plt.figure(figsize=figsize)
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    return fig, ax3, ax2


def line3(ax, r: np.ndarray, *args, **kw):
    """``ax.plot`` of points r (3, n) on 3-D axes."""
    return ax.plot(r[0], r[1], r[2], *args, **kw)


def figure_static(positions: np.ndarray, reference: np.ndarray, title: str = ""):
    """The static equilibrium (solid, nodes marked) and the stress-free reference
    (dashed grey), in 3-D and projected."""
    fig, ax3, ax2 = two_views()
    pts = np.hstack([positions, reference])
    line3(ax3, reference, "--", color=GREY, lw=1.0, label="reference")
    line3(ax3, positions, "-", color="C0", lw=1.6, label="equilibrium")
    line3(ax3, positions[:, [0, -1]], "o", color="C0", ms=3)
    equal_axes_3d(ax3, pts)
    a, b = projection_axes(ax2, pts)
    ax2.plot(reference[a], reference[b], "--", color=GREY, lw=1.0, label="reference")
    ax2.plot(positions[a], positions[b], ".-" if positions.shape[1] <= 61 else "-",
             color="C0", lw=1.6, ms=3, label="equilibrium")
    ax2.legend(fontsize=8, loc="best")
    fig.suptitle(title or "static equilibrium", fontsize=10)
    fig.tight_layout()
    return fig


def plot_static(positions: np.ndarray, reference: np.ndarray, path: Path,
                title: str = "") -> Path:
    """:func:`figure_static` as PNG."""
    return save(figure_static(positions, reference, title), path, dpi=110)


def snapshot_indices(m: int, count: int = RUN_SNAPSHOTS) -> np.ndarray:
    """``count`` frame indices spread evenly over ``m`` frames, first and last included."""
    if m <= count:
        return np.arange(m)
    return np.unique(np.round(np.linspace(0, m - 1, count)).astype(int))


def figure_run_centreline(t: np.ndarray, frames: np.ndarray, reference: np.ndarray,
                          title: str = "", count: int = RUN_SNAPSHOTS):
    """The run's centreline at ``count`` frame times (colour: time, colour bar in s) and
    the stress-free reference (dashed grey), in 3-D and projected."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    plt = pyplot()
    idx = snapshot_indices(frames.shape[0], count)
    t0, t1 = float(t[0]), float(t[-1])
    norm = Normalize(t0, t1 if t1 > t0 else t0 + 1.0)
    cmap = plt.get_cmap("viridis")
    fig, ax3, ax2 = two_views(figsize=(11.5, 4.6))
    pts = np.hstack([reference, *frames[idx]])
    for i in idx:
        line3(ax3, frames[i], "-", color=cmap(norm(t[i])), lw=1.3)
    line3(ax3, reference, "--", color=GREY, lw=1.0, zorder=5)   # on top: visible at rest
    equal_axes_3d(ax3, pts)
    a, b = projection_axes(ax2, pts)
    for i in idx:
        ax2.plot(frames[i][a], frames[i][b], "-", color=cmap(norm(t[i])), lw=1.3)
    ax2.plot(reference[a], reference[b], "--", color=GREY, lw=1.0, label="reference",
             zorder=5)
    ax2.legend(fontsize=8, loc="best")
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax2, label="time t [s]",
                 shrink=0.85)
    fig.suptitle(f"{title + ': ' if title else ''}deformed centreline at {idx.size} of "
                 f"{frames.shape[0]} frames, t = {t0:g} ... {t1:g} s", fontsize=10)
    fig.tight_layout()
    return fig


def plot_run_centreline(t: np.ndarray, frames: np.ndarray, reference: np.ndarray,
                        path: Path, title: str = "") -> Path:
    """:func:`figure_run_centreline` as PNG."""
    return save(figure_run_centreline(t, frames, reference, title), path, dpi=110)


def mode_amplitude(displacement: np.ndarray, rotation: np.ndarray, length: float) -> float:
    """The factor that draws a mass-normalised mode shape visibly: its largest node
    displacement :data:`MODE_DISPLACEMENT` times ``length`` or its largest segment
    rotation :data:`MODE_ROTATION` rad, whichever comes first (0 for a zero shape)."""
    cands = []
    d = float(np.max(np.abs(displacement))) if displacement.size else 0.0
    r = float(np.max(np.abs(rotation))) if rotation.size else 0.0
    if d > 0:
        cands.append(MODE_DISPLACEMENT * length / d)
    if r > 0:
        cands.append(MODE_ROTATION / r)
    return min(cands) if cands else 0.0


def _rotate(frames: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Frames (N, 3, 3) rotated by material rotation vectors theta (3, N):
    R exp([theta]x) (Rodrigues)."""
    th = theta.T
    ang = np.linalg.norm(th, axis=1)
    out = np.array(frames, dtype=float)
    for j in np.flatnonzero(ang > 0):
        k = th[j] / ang[j]
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        E = np.eye(3) + math.sin(ang[j]) * K + (1 - math.cos(ang[j])) * K @ K
        out[j] = frames[j] @ E
    return out


def _mode_title(m: dict) -> str:
    z = m.get("zeta")
    zs = "-" if z is None or (isinstance(z, float) and not math.isfinite(z)) else (
        f"{float(z):.3g}")
    f = float(m.get("frequency_hz", m.get("omega", 0.0) / (2 * math.pi)))
    return (f"mode {m['index']}: {m['family']} ({m.get('family_index', '')})\n"
            f"f = {f:.4g} Hz, zeta = {zs}")


def figure_mode_shapes_3d(mf, max_modes: int = MAX_MODES):
    """The first ``max_modes`` mode shapes of a :class:`runtime.io.modes.ModesFile`:
    equilibrium dashed grey, the shape at +/- the amplitude of :func:`mode_amplitude`
    (solid / faint), and for torsion modes the director d1 at a few segments (the
    centreline of a torsion mode hardly moves). Equal axes, one cube for all modes."""
    plt = pyplot()
    k = min(len(mf.modes), max_modes)
    eq = mf.equilibrium if mf.equilibrium is not None else mf.reference
    if eq is None:   # format 1 without the equilibrium: a straight rod along z
        n = mf.displacement.shape[2]
        eq = np.vstack([np.zeros((2, n)), np.linspace(0.0, mf.length, n)])
    L = mf.length
    cols = min(4, max(k, 1))
    rows = max(1, math.ceil(k / cols))
    fig = plt.figure(figsize=(3.4 * cols, 3.5 * rows + 0.6))
    shapes = []
    for j in range(k):
        d, r = mf.displacement[j], mf.rotation[j]
        a = mode_amplitude(d, r, L)
        shapes.append((a, eq + a * d, eq - a * d))
    pts = np.hstack([eq] + [s[1] for s in shapes] + [s[2] for s in shapes])
    tick = 0.08 * L
    for j in range(k):
        a, plus, minus = shapes[j]
        ax = fig.add_subplot(rows, cols, j + 1, projection="3d")
        line3(ax, eq, "--", color=GREY, lw=0.9)
        line3(ax, minus, "-", color="C0", lw=0.8, alpha=0.35)
        line3(ax, plus, ".-", color="C0", lw=1.4, ms=2)
        m = mf.modes[j]
        if m.get("family") == "torsion" and mf.equilibrium_frames is not None:
            rot = _rotate(mf.equilibrium_frames, a * mf.rotation[j])
            mids = (plus[:, :-1] + plus[:, 1:]) / 2
            for s in snapshot_indices(mids.shape[1], 9):
                for frames, color in ((mf.equilibrium_frames, GREY), (rot, "C3")):
                    seg = np.column_stack([mids[:, s], mids[:, s] + tick * frames[s][:, 0]])
                    line3(ax, seg, "-", color=color, lw=1.0)
        equal_axes_3d(ax, pts)
        ax.set_title(_mode_title(m), fontsize=8)
    meta = mf.meta
    about = "static equilibrium under the loads" if meta.get("deformed") else "reference"
    more = f" (first {k} of {len(mf.modes)})" if len(mf.modes) > k else ""
    fig.suptitle(f"{meta.get('problem', 'modes')}: mode shapes{more} about the {about} "
                 f"(dashed), scaled to a largest displacement of {MODE_DISPLACEMENT:g} L "
                 f"or rotation of {MODE_ROTATION:g} rad; torsion: director d1 (red; grey: at rest)",
                 fontsize=9)
    # fixed margins: tight_layout of 3-D axes costs a full draw (~0.1 s per axes)
    fig.subplots_adjust(left=0.02, right=0.96, bottom=0.04, top=1 - 0.7 / fig.get_figheight(),
                        wspace=0.15, hspace=0.3)
    return fig


def plot_mode_shapes_3d(mf, path: Path, max_modes: int = MAX_MODES) -> Path:
    """:func:`figure_mode_shapes_3d` as PNG."""
    return save(figure_mode_shapes_3d(mf, max_modes), path, dpi=100)


def figure_mode_components(mf, max_modes: int = MAX_MODES):
    """Mode shapes along the rod: node displacements (solid) and segment rotations times
    L (dashed) against the arc length s, scaled together to a largest value of 1;
    components below 1e-6 of the largest are left out."""
    plt = pyplot()
    n = min(len(mf.modes), max_modes)
    cols = min(3, max(n, 1))
    rows = max(1, math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.8 * rows), squeeze=False)
    length = mf.length
    for j, ax in enumerate(axes.ravel()[:n]):
        m = mf.modes[j]
        N = mf.rotation.shape[2]
        s_n = np.linspace(0.0, length, N + 1)
        s_s = (s_n[:-1] + s_n[1:]) / 2
        d, r = mf.displacement[j], mf.rotation[j] * length  # rotations as theta L (m)
        scale = max(np.abs(d).max(), np.abs(r).max()) or 1.0
        for c, lab in enumerate(("x", "y", "z")):
            if np.abs(d[c]).max() > 1e-6 * scale:
                ax.plot(s_n, d[c] / scale, "-", color=f"C{c}", label=f"u_{lab}")
            if np.abs(r[c]).max() > 1e-6 * scale:
                ax.plot(s_s, r[c] / scale, "--", color=f"C{c}", label=f"theta_{c + 1} L")
        ax.set_title(_mode_title(m).replace("\n", ", "), fontsize=8)
        ax.set_xlabel("s [m]", fontsize=8)
        ax.set_ylabel("shape (scaled) [-]", fontsize=8)
        ax.tick_params(labelsize=7)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6, loc="best")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig


def plot_mode_components(mf, path: Path, max_modes: int = MAX_MODES) -> Path:
    """:func:`figure_mode_components` as PNG."""
    return save(figure_mode_components(mf, max_modes), path, dpi=110)


# --------------------------------------------------------------------------------------
# animation
# --------------------------------------------------------------------------------------

ANIMATION_FORMATS = ("gif", "mp4")


def animation_unavailable(fmt: str) -> str | None:
    """Why an animation in ``fmt`` cannot be written here, or None: MP4 needs ffmpeg on
    PATH (GIF needs only Pillow, a dependency of matplotlib)."""
    if fmt not in ANIMATION_FORMATS:
        return f"unknown animation format {fmt!r}: one of {', '.join(ANIMATION_FORMATS)}"
    if fmt == "mp4" and shutil.which("ffmpeg") is None:
        return ("MP4 needs ffmpeg on PATH, which was not found (install ffmpeg, e.g. "
                "`apt-get install ffmpeg`, or ask for a GIF: --animate gif)")
    return None


def render_frames(fig, artists: Sequence, update, count: int):
    """Yield the figure as RGBA arrays (h, w, 4) for ``count`` frames: the static parts
    drawn once, then per frame ``update(i)`` and only the ``artists`` redrawn over a copy
    of that background (matplotlib's blitting). A full redraw of the 3-D axes and their
    ticks costs ~0.15 s a frame here; this ~100 times less, which is why this does not
    use ``FuncAnimation.save`` (it redraws every frame)."""
    canvas = fig.canvas
    for a in artists:
        a.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    for i in range(count):
        canvas.restore_region(background)
        update(i)
        for a in artists:
            (a.axes or fig).draw_artist(a)
        canvas.blit(fig.bbox)
        yield np.array(canvas.buffer_rgba())


def write_gif(frames, path: Path, fps: int) -> None:
    """GIF through Pillow (what matplotlib's PillowWriter does with its frames)."""
    from PIL import Image

    # opaque frames (a GIF palette has no partial transparency: the 3-D panes would
    # vanish) on one palette without dithering: the frames differ only where the rod
    # moves, which keeps the file small (dithered per-frame palettes: ~5x larger)
    images = [Image.fromarray(f, "RGBA").convert("RGB") for f in frames]
    palette = images[0].quantize(colors=96, dither=Image.Dither.NONE)
    images = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=int(1000 / fps), loop=0)


def write_mp4(frames, path: Path, fps: int) -> None:
    """H.264 MP4 through the ffmpeg command line (raw RGBA frames on its stdin, as
    matplotlib's FFMpegWriter sends them)."""
    import subprocess

    from matplotlib import rcParams

    proc = None
    try:
        for f in frames:
            if proc is None:
                h, w = f.shape[:2]
                proc = subprocess.Popen(
                    [rcParams["animation.ffmpeg_path"], "-y", "-loglevel", "error",
                     "-f", "rawvideo", "-pix_fmt", "rgba", "-s", f"{w}x{h}",
                     "-framerate", str(fps), "-i", "pipe:", "-vf",
                     "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-vcodec", "libx264", "-pix_fmt",
                     "yuv420p", "-f", "mp4", str(path)],
                    stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            proc.stdin.write(np.ascontiguousarray(f).tobytes())
    finally:
        if proc is not None:
            _, err = proc.communicate()
            if proc.returncode != 0:
                raise OSError(f"ffmpeg failed writing {str(path)!r}: "
                              f"{' '.join(err.decode(errors='replace').split())[:300]}")


def animate_run(t: np.ndarray, frames: np.ndarray, reference: np.ndarray, path: Path,
                title: str = "", fps: int = 20) -> Path:
    """The run's centreline frames as an animation (GIF or MP4 by ``path``'s suffix),
    3-D view and projection with fixed, equal axes; the reference dashed grey. At most
    :data:`MAX_ANIMATION_FRAMES` frames (evenly subsampled). Raises ValueError naming
    the format when it cannot be written here (:func:`animation_unavailable`)."""
    from runtime.io.atomic import atomic_path

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    why = animation_unavailable(fmt)
    if why is not None:
        raise ValueError(why)
    idx = snapshot_indices(frames.shape[0], MAX_ANIMATION_FRAMES)
    fig, ax3, ax2 = two_views(figsize=(9.0, 4.2))
    fig.set_dpi(80)
    pts = np.hstack([reference, *frames[idx]])
    line3(ax3, reference, "--", color=GREY, lw=1.0)
    curve3, = line3(ax3, frames[idx[0]], "-", color="C0", lw=1.6)
    equal_axes_3d(ax3, pts)
    a, b = projection_axes(ax2, pts)
    ax2.plot(reference[a], reference[b], "--", color=GREY, lw=1.0, label="reference")
    line2, = ax2.plot(frames[idx[0]][a], frames[idx[0]][b], "-", color="C0", lw=1.6,
                      label="centreline")
    ax2.legend(fontsize=8, loc="upper right")
    # the projection's limits must hold every frame (set_aspect adjusts around them)
    ax2.update_datalim(np.column_stack([pts[a], pts[b]]))
    ax2.autoscale_view()
    fig.suptitle(title or "run", fontsize=10)
    stamp = ax2.text(0.02, 0.97, "", transform=ax2.transAxes, va="top", fontsize=9)
    fig.tight_layout()

    def update(i: int) -> None:
        r = frames[idx[i]]
        curve3.set_data_3d(r[0], r[1], r[2])
        line2.set_data(r[a], r[b])
        stamp.set_text(f"t = {float(t[idx[i]]):.4g} s")

    try:
        rendered = render_frames(fig, (curve3, line2, stamp), update, idx.size)
        with atomic_path(path, suffix=path.suffix) as tmp:
            (write_gif if fmt == "gif" else write_mp4)(rendered, tmp, fps)
    finally:
        pyplot().close(fig)
    return path

"""Shapes you can see (issue 23, item 5): centreline frames of a run, one modes.json format
with mode shapes, `kvrod plot` for every kind of results folder, plots checked as pictures
(pixel size, not blank, axes labelled)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from kvrod.cli import main
from runtime.errors import ParameterError
from runtime.problem.registry import load_problem
from runtime.simulate.simulate import simulate

PIL = pytest.importorskip("PIL.Image")


# --------------------------------------------------------------------------------------
# helpers: a figure's labels, a PNG as a picture
# --------------------------------------------------------------------------------------


def assert_labelled(fig) -> None:
    """Every visible axes of ``fig`` has x and y labels (and z for 3-D; the x label may
    be on an axes it shares x with) and a drawing."""
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    assert axes
    for ax in axes:
        assert any(a.get_xlabel().strip() for a in ax.get_shared_x_axes().get_siblings(ax))
        assert ax.get_ylabel().strip(), ax
        if ax.name == "3d":
            assert ax.get_zlabel().strip()
        assert ax.lines or ax.collections, ax


def assert_equal_3d(fig) -> None:
    """3-D axes have equal data spans on x, y, z in a cubic box (shapes undistorted)."""
    for ax in fig.axes:
        if ax.name != "3d":
            continue
        spans = [np.ptp(lim) for lim in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
        assert np.allclose(spans, spans[0], rtol=1e-9), spans
        assert np.allclose(ax.get_box_aspect(), ax.get_box_aspect()[0])


def picture(path: Path, size: tuple[int, int] | None = None,
            min_size: tuple[int, int] = (400, 250)) -> np.ndarray:
    """The PNG as an RGB array, checked: it exists, has the pixel size expected (exact,
    or at least ``min_size``) and is not blank (pixel variance, enough drawn pixels)."""
    assert path.is_file(), path
    with PIL.open(path) as im:
        assert im.format == "PNG"
        if size is not None:
            assert im.size == size, (path.name, im.size)
        assert im.size[0] >= min_size[0] and im.size[1] >= min_size[1], (path.name, im.size)
        rgb = np.asarray(im.convert("RGB"), dtype=float)
    assert rgb.std() > 10.0, f"{path.name} looks blank"
    drawn = np.any(np.abs(rgb - 255.0) > 30, axis=2).mean()
    assert 0.01 < drawn < 0.9, (path.name, drawn)
    return rgb


def run_cli(argv, capsys) -> tuple[int, str, str]:
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


# --------------------------------------------------------------------------------------
# centreline frames of a run
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def small():
    return load_problem("cantilever", {"n_elements": 8, "t_end": 1.2, "rtol": 1e-7,
                                       "simulation.centreline_frames": 25})


def test_centreline_frames_on_their_grid(small):
    run = simulate(small)
    assert run.status == "finished"
    assert run.centreline.shape == (25, 3, 9)
    assert np.allclose(run.centreline_t, np.linspace(0, 1.2, 25), rtol=0, atol=1e-15)
    # the free end's frames are the sampled tip series where the grids meet (both are
    # read from the same interpolant); the clamped node does not move
    for j, t in enumerate(run.centreline_t):
        k = np.flatnonzero(np.isclose(run.t, t, rtol=0, atol=1e-12))
        if k.size:
            assert np.allclose(run.centreline[j][:, -1], run.tip[:, k[0]], rtol=0, atol=1e-12)
    assert np.ptp(run.centreline[:, :, 0], axis=0).max() == 0.0
    # the frame at t = 0 is the static equilibrium the run starts from
    assert np.allclose(run.centreline[0], run.model.positions(run.y_static), atol=1e-12)
    # the rod swings: the tip moves by a good fraction of its 0.22 m initial deflection
    assert np.ptp(run.centreline[:, 0, -1]) > 0.2


def test_frames_of_a_moving_clamp_are_at_its_prescribed_positions():
    p = load_problem("examples/base_excitation.toml", {"n_elements": 6, "t_end": 0.3,
                                                       "simulation.centreline_frames": 7})
    run = simulate(p)
    assert run.status == "finished"
    moved = 0.0
    for j, t in enumerate(run.centreline_t):
        k = np.flatnonzero(np.isclose(run.t, t, rtol=0, atol=1e-12))
        assert k.size
        assert np.allclose(run.centreline[j][:, 0], run.start[:, k[0]], rtol=0, atol=1e-15)
        moved = max(moved, float(np.abs(run.start[:, k[0]] - run.start[:, 0]).max()))
    assert moved > 1e-4        # the clamp did move


def test_frames_do_not_change_the_run(small):
    a = simulate(small)
    b = simulate(small.with_overrides({"simulation.centreline_frames": 0}))
    assert b.centreline.shape[0] == 0
    assert a.counters == b.counters and np.array_equal(a.tip, b.tip)


def test_checkpoint_and_resume_keep_the_frames(small, tmp_path):
    from runtime.io.results import load_checkpoint, write_checkpoint

    params = small.to_mapping()
    saved = []

    def keep_first(state):
        if not saved:
            write_checkpoint(tmp_path, params, state)
            saved.append(float(state["t"]))

    full = simulate(small, checkpoint=keep_first, checkpoint_every=0.5)
    state = load_checkpoint(tmp_path, params)
    k = int(state["centreline_k"])
    assert 0 < k < 25 and saved[0] >= full.centreline_t[k - 1]
    resumed = simulate(small, resume=state)
    assert resumed.centreline.shape == full.centreline.shape
    assert np.array_equal(resumed.centreline_t, full.centreline_t)
    # before the checkpoint: the stored frames themselves; after: the same motion to
    # the integrator's tolerance (the multistep history restarts at the checkpoint)
    assert np.array_equal(resumed.centreline[:k], full.centreline[:k])
    assert np.max(np.abs(resumed.centreline - full.centreline)) < 1e-4


def test_centreline_frames_key_is_checked():
    with pytest.raises(ParameterError, match="centreline_frames"):
        load_problem("cantilever", {"simulation.centreline_frames": 1})
    with pytest.raises(ParameterError, match="centreline_frames"):
        load_problem("cantilever", {"simulation.centreline_frames": -3})
    with pytest.raises(ParameterError, match="centreline_frames.*elements"):
        load_problem("cantilever", {"simulation.centreline_frames": 10_000,
                                    "n_elements": 5000})
    assert load_problem("cantilever").simulation.centreline_frames == 101


# --------------------------------------------------------------------------------------
# modes: one format, the shapes in modes.npz
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def modes_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("modes") / "m"
    assert main(["modes", "cantilever", "--n-elements", "8", "--count", "7", "--plots",
                 "--out", str(out)]) == 0
    return out


def test_modes_files_one_format(modes_dir):
    from runtime.analysis.modal import modal_analysis
    from runtime.io.modes import FORMAT, read_modes
    from runtime.problem.assemble import build_model

    js = json.loads((modes_dir / "modes.json").read_text())
    assert js["format"] == FORMAT and js["shapes"] == "modes.npz"
    assert {"problem", "parameters", "tau_E", "deformed", "static_tip"} <= set(js)
    assert all("displacement" not in m and "frequency_hz" in m for m in js["modes"])
    mf = read_modes(modes_dir)
    assert mf.displacement.shape == (7, 3, 9) and mf.rotation.shape == (7, 3, 8)
    assert mf.equilibrium_frames.shape == (8, 3, 3)
    assert np.allclose(mf.equilibrium, mf.reference)         # straight, unloaded
    assert mf.length == pytest.approx(0.3)
    # the shapes are those of the analysis (whose sign is fixed: runtime/analysis/modal.py)
    from dataclasses import replace

    p = replace(load_problem("cantilever", {"n_elements": 8}), loads=())
    modes = modal_analysis(build_model(p), count=7)
    for j, m in enumerate(modes):
        assert np.allclose(mf.displacement[j], m.displacement, rtol=1e-6, atol=1e-9)
        assert np.allclose(mf.rotation[j], m.rotation, rtol=1e-6, atol=1e-9)


def test_modes_json_has_one_writer():
    """Every modes.json is written by runtime/io/modes.py (three writers before)."""
    root = Path(__file__).resolve().parents[2]
    writers = []
    for f in sorted([*root.joinpath("kvrod").rglob("*.py"),
                     *root.joinpath("runtime").rglob("*.py")]):
        for line in f.read_text().splitlines():
            if "modes.json" in line and ("write_json" in line or "write_text" in line):
                writers.append(f.relative_to(root).as_posix())
    assert writers == [], writers
    assert "JSON_NAME" in root.joinpath("runtime/io/modes.py").read_text()


def test_read_modes_of_the_earlier_format(modes_dir, tmp_path):
    """modes.json as kvrod wrote it before modes.npz (shapes inside, no format)."""
    from runtime.io.modes import read_modes
    from runtime.io.shapes import figure_mode_shapes_3d

    mf = read_modes(modes_dir)
    js = json.loads((modes_dir / "modes.json").read_text())
    del js["format"], js["shapes"]
    for m, d, r in zip(js["modes"], mf.displacement, mf.rotation, strict=True):
        m["displacement"], m["rotation"] = d.tolist(), r.tolist()
    (tmp_path / "modes.json").write_text(json.dumps(js))
    old = read_modes(tmp_path)
    assert np.array_equal(old.displacement, mf.displacement) and old.equilibrium is None
    fig = figure_mode_shapes_3d(old)
    assert_labelled(fig)


# --------------------------------------------------------------------------------------
# figures as objects: labels, equal axes, legend and limits
# --------------------------------------------------------------------------------------


def test_run_figures_labelled_legend_clear_limits_with_margins(small):
    from runtime.io import plots, shapes

    run = simulate(small.with_overrides({"simulation.t_end": 3.0}))
    fig = plots.figure_energy(run)
    assert_labelled(fig)
    fig.canvas.draw()
    legend = fig.axes[0].get_legend()
    lb, ab = legend.get_window_extent(), fig.axes[0].get_window_extent()
    assert lb.x0 >= ab.x1 or not lb.overlaps(ab)      # the legend is beside the data
    shapes.pyplot().close(fig)
    zlin = run.problem.linear_prediction()["zeta_1"]
    fig = plots.figure_damping_vs_amplitude([run], ["run"], [zlin])
    assert_labelled(fig)
    lo, hi = fig.axes[0].get_ylim()
    z = np.r_[plots.damping_ratios(plots.log_decrements(run.peaks_x)), zlin]
    margin = 0.05 * (z.max() - z.min())
    assert lo < z.min() - margin and hi > z.max() + margin   # no line on the frame
    shapes.pyplot().close(fig)
    fig = shapes.figure_run_centreline(run.centreline_t, run.centreline,
                                       run.model.positions(run.model.reference), "run")
    assert_labelled(fig)
    assert_equal_3d(fig)
    assert "8 of 25 frames" in fig.get_suptitle()
    shapes.pyplot().close(fig)


def test_mode_figures_labelled_and_equal(modes_dir):
    from runtime.io.modes import read_modes
    from runtime.io.shapes import (
        figure_mode_components,
        figure_mode_shapes_3d,
        mode_amplitude,
        pyplot,
    )

    mf = read_modes(modes_dir)
    fig = figure_mode_shapes_3d(mf)
    assert_labelled(fig)
    assert_equal_3d(fig)
    titles = [ax.get_title() for ax in fig.axes]
    assert len(titles) == 7
    for t, m in zip(titles, mf.modes, strict=True):   # family, frequency, damping ratio
        assert m["family"] in t and f"{m['frequency_hz']:.4g} Hz" in t and "zeta =" in t
    pyplot().close(fig)
    for j in range(7):    # drawn at a visible amplitude: 0.2 L or 0.6 rad
        a = mode_amplitude(mf.displacement[j], mf.rotation[j], mf.length)
        big = max(a * np.abs(mf.displacement[j]).max() / (0.2 * mf.length),
                  a * np.abs(mf.rotation[j]).max() / 0.6)
        assert big == pytest.approx(1.0)
    fig = figure_mode_components(mf)
    assert_labelled(fig)
    pyplot().close(fig)


# --------------------------------------------------------------------------------------
# kvrod plot on every kind of folder: pictures on disk
# --------------------------------------------------------------------------------------


def test_plot_a_run_folder_and_animate(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "cantilever", "--n-elements", "8", "--t-end", "3",
                 "--set", "simulation.centreline_frames=31", "--out", str(out)]) == 0
    with np.load(out / "series.npz") as f:
        assert f["centreline"].shape == (31, 3, 9) and f["reference"].shape == (3, 9)
    capsys.readouterr()
    rc, stdout, _ = run_cli(["plot", out, "--animate"], capsys)
    assert rc == 0 and "run result" in stdout
    for name in ("ends.png", "energy.png", "damping_ratio.png"):
        picture(out / name)
    picture(out / "centreline.png", size=(1265, 506))          # 11.5 x 4.6 in at 110 dpi
    with PIL.open(out / "centreline.gif") as gif:
        assert gif.n_frames == 31 and gif.size == (720, 336)   # 9 x 4.2 in at 80 dpi
        gif.seek(0)
        first = np.asarray(gif.convert("RGB"), dtype=float)
        gif.seek(30)
        last = np.asarray(gif.convert("RGB"), dtype=float)
    assert first.std() > 10 and np.abs(first - last).max() > 0   # the rod moves


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg not on PATH")
def test_animate_mp4_with_ffmpeg(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "cantilever", "--n-elements", "6", "--t-end", "1",
                 "--set", "simulation.centreline_frames=11", "--out", str(out)]) == 0
    rc, _, err = run_cli(["plot", out, "--animate", "mp4"], capsys)
    assert rc == 0, err
    head = (out / "centreline.mp4").read_bytes()[:12]
    assert head[4:8] == b"ftyp"                                  # an MP4 container


def test_animate_mp4_without_ffmpeg_says_so(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    assert main(["simulate", "cantilever", "--n-elements", "4", "--t-end", "0.5",
                 "--set", "simulation.centreline_frames=5", "--out", str(out)]) == 0
    monkeypatch.setattr(shutil, "which", lambda name, *a, **k: None)
    capsys.readouterr()
    rc, _, err = run_cli(["plot", out, "--animate", "mp4"], capsys)
    assert rc == 2 and "ffmpeg" in err and "--animate gif" in err
    assert len(err.strip().splitlines()) == 1 and err.startswith("kvrod plot")
    assert not list(out.glob("*.png"))                 # refused before drawing anything


def test_plot_a_run_without_frames(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "cantilever", "--n-elements", "4", "--t-end", "0.5",
                 "--set", "simulation.centreline_frames=0", "--out", str(out)]) == 0
    capsys.readouterr()
    rc, stdout, _ = run_cli(["plot", out], capsys)
    assert rc == 0 and "no centreline.png" in stdout
    assert not (out / "centreline.png").exists()
    rc, _, err = run_cli(["plot", out, "--animate"], capsys)
    assert rc == 2 and "centreline_frames" in err


def test_plot_a_static_folder(tmp_path, capsys):
    out = tmp_path / "static"
    assert main(["static", "cantilever", "--n-elements", "8", "--out", str(out)]) == 0
    capsys.readouterr()
    rc, stdout, _ = run_cli(["plot", out], capsys)
    assert rc == 0 and "static result" in stdout
    picture(out / "shape.png", size=(1155, 506))               # 10.5 x 4.6 in at 110 dpi
    from runtime.io.shapes import figure_static, pyplot

    with np.load(out / "static.npz") as f:
        fig = figure_static(f["positions"], f["reference"])
    assert_labelled(fig)
    assert_equal_3d(fig)
    pyplot().close(fig)
    rc, _, err = run_cli(["plot", out, "--animate"], capsys)
    assert rc == 2 and "--animate draws a run" in err


def test_plot_a_modes_folder(modes_dir, capsys):
    for name in ("mode_shapes.png", "mode_shapes_3d.png"):
        (modes_dir / name).unlink()
    rc, stdout, _ = run_cli(["plot", modes_dir], capsys)
    assert rc == 0 and "modes result" in stdout
    picture(modes_dir / "mode_shapes.png")
    picture(modes_dir / "mode_shapes_3d.png", size=(1360, 760))  # 4 x 2 panels at 100 dpi


def test_plot_a_sweep_folder(tmp_path, capsys):
    from runtime.study.sweep import load_study, run_study_serial

    f = tmp_path / "study.toml"
    f.write_text('problem = "cantilever"\n[fixed]\nt_end = 4.0\nn_elements = 4\n'
                 '[grid]\ntau = [0.02, 0.04]\n')
    out = tmp_path / "sweep"
    run_study_serial(load_study(f), out, plots=False)
    rc, stdout, _ = run_cli(["plot", out], capsys)
    assert rc == 0 and "sweep result" in stdout and "points" in stdout
    picture(out / "summary.png")


def test_plot_says_what_it_cannot_plot(tmp_path, capsys):
    rc, _, err = run_cli(["plot", tmp_path / "nothing"], capsys)
    assert rc == 2 and "does not exist" in err
    (tmp_path / "empty").mkdir()
    rc, _, err = run_cli(["plot", tmp_path / "empty"], capsys)
    assert rc == 2 and "holds no kvrod result" in err and "static.npz" in err
    # a folder of results (reproduce, notes-*): names them
    outer = tmp_path / "outer"
    assert main(["static", "cantilever", "--n-elements", "4", "--out", str(outer / "a")]) == 0
    capsys.readouterr()
    rc, _, err = run_cli(["plot", outer], capsys)
    assert rc == 2 and "subfolders a do" in err and "kvrod plot" in err
    # results whose figures come with their command (the markers they write)
    for marker, command in (("compare_damping.json", "kvrod compare-damping"),
                            ("calibration.json", "kvrod calibrate"),
                            ("dma.json", "kvrod calibrate --dma")):
        d = tmp_path / marker.split(".")[0]
        d.mkdir()
        (d / marker).write_text("{}")
        rc, _, err = run_cli(["plot", d], capsys)
        assert rc == 2 and f"`{command}` result" in err and "not stored" in err
        assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("n_moduli, colour_bar", [(3, False), (12, True)])
def test_sweep_summary_names_few_lines_and_colours_many(n_moduli, colour_bar, tmp_path,
                                                        monkeypatch):
    """summary.png: up to LEGEND_MAX lines get a legend entry each (first and last
    cycle); more get a colour scale with a colour bar labelled with the other parameter,
    and a two-entry legend for the line styles."""
    from runtime.io import figures
    from runtime.study.plots import LEGEND_MAX, write_plots
    from runtime.study.points import slug_value
    from runtime.study.sweep import study_from_dict

    assert (n_moduli > LEGEND_MAX) == colour_bar
    s = study_from_dict({"problem": "cantilever", "fixed": {"n_elements": 4},
                         "grid": {"tau": [0.01, 0.02, 0.03],
                                  "youngs_modulus": [1e6 * (n_moduli - i)   # descending
                                                     for i in range(n_moduli)]}})
    rows = {p.id: {**p.params, "status": "finished", "zeta_first": 0.1 + p.params["tau"],
                   "zeta_last": 0.1, "period_mean": 1e3 / p.params["youngs_modulus"] ** 0.5}
            for p in s.points}
    drawn = []
    real_save = figures.save
    monkeypatch.setattr(figures, "save", lambda fig, path, **kw: (drawn.append(fig),
                                                                  real_save(fig, path, **kw))[1])
    path = write_plots(tmp_path, s, rows)
    fig, = drawn
    picture(path)
    assert_labelled(fig)
    ax1 = fig.axes[0]
    entries = [t.get_text() for t in ax1.get_legend().get_texts()]
    if colour_bar:
        assert len(fig.axes) == 3 and entries == ["first cycle", "last cycle"]
        assert fig.axes[2].get_ylabel() == "youngs_modulus [Pa]"
        colours = {tuple(line.get_color()) for line in ax1.lines}
        assert len(colours) == n_moduli                     # one colour a line
        # the colour is the modulus's value on a logarithmic scale (1e6 ... 1.2e7), so
        # it does not depend on the grid's order or on which points have finished
        import matplotlib as mpl
        import numpy as np

        by_label = {line.get_label(): line.get_color() for line in ax1.lines}
        viridis = mpl.colormaps["viridis"]
        for e, at in ((1e6, 0.0), (1.2e7, 1.0), (4e6, np.log(4) / np.log(12))):
            got = by_label[f"first youngs_modulus={slug_value(e)}"]
            assert np.allclose(got, viridis(at), atol=0.01), (e, got)
    else:
        assert len(fig.axes) == 2 and len(entries) == 2 * n_moduli
        assert entries[0] == f"first youngs_modulus={slug_value(3e6)}"   # study order

"""The draped cord and the wire pushed through a bend (issue 32, item 5) against their
references written separately (references/contact.py): the cord over a cylinder holds
below the friction's overhang limit and slides above it, the cylinder carries the cord's
weight and the friction's moment; the entry of the bend carries F_out exp(mu theta). Also
the per obstacle outputs of an assembly (series, summary, statics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references import contact as ref
from runtime.problem.registry import load_problem
from runtime.simulate.assembly import simulate_assembly
from runtime.simulate.simulate import simulate

R_CORD = 0.10113          # m: the cord's centreline on the cylinder (the example's arc)
H_LOW, H_HIGH = 0.5, 0.9  # m: the example's two strands


def _cord_weight_per_length(p) -> float:
    rod = p.rods["left"]
    r = dict(rod.section.dims)["radius"]
    return rod.material.density * math.pi * r * r * 9.81


@pytest.fixture(scope="module")
def draped_held():
    p = load_problem("contact_draped_cable", {"simulation.t_end": 1.0})
    return p, simulate_assembly(p)


def test_the_draped_cord_holds_below_the_friction_limit(draped_held):
    """mu = 0.2: the heavier side may hang up to h_high = 1.049 m, so 0.9 m holds (the
    regularised friction lets it creep: below 0.5 mm over the last half second)."""
    p, res = draped_held
    assert res.status == "finished", res.message
    assert ref.draped_cable_max_overhang(H_LOW, R=R_CORD, mu=0.2) > H_HIGH
    z = res.ends["right/end"][2]
    late = res.t >= 0.5
    assert np.ptp(z[late]) < 5e-4
    assert res.audit().max_rel < 1e-4


def test_the_cylinder_carries_the_cords_weight_and_the_frictions_moment(draped_held):
    """Global balance of the resting cord: the cylinder's force is the weight q (h_low +
    h_high + pi R) and its moment about its axis the difference of the strands' tensions
    times R, q (h_high - h_low) R (the cord's overhangs grow by its sag into the cylinder
    and its stretch, about 1e-3)."""
    p, res = draped_held
    q = _cord_weight_per_length(p)
    summary = res.summary()["obstacles"][0]
    force, moment = np.array(summary["force"]["final"]), np.array(summary["moment"]["final"])
    assert force[2] == pytest.approx(q * (H_LOW + H_HIGH + math.pi * R_CORD), rel=1e-3)
    assert abs(force[0]) < 1e-3 * force[2] and abs(force[1]) < 1e-3 * force[2]  # swinging
    assert -moment[1] == pytest.approx(q * (H_HIGH - H_LOW) * R_CORD, rel=1e-2)
    series = res.obstacle_series()[0]
    assert series["force"].shape == (3, res.t.size)
    assert np.all(series["segments"][res.t > 0.2] > 0)


def test_the_draped_cord_slides_off_above_the_friction_limit():
    """mu = 0.1: h_high = 0.732 m < 0.9 m: the heavier side runs down (more than 2 cm in
    0.3 s, where holding it creeps by well under a millimetre)."""
    assert ref.draped_cable_max_overhang(H_LOW, R=R_CORD, mu=0.1) < H_HIGH
    p = load_problem("contact_draped_cable", {"simulation.t_end": 0.3,
                                              "obstacles.0.friction": 0.1})
    res = simulate_assembly(p)
    assert res.status == "finished", res.message
    z = res.ends["right/end"][2]
    assert z[0] - z[-1] > 0.02


def test_a_wire_pushed_through_a_bend_needs_the_capstan_force():
    """The entry of a 90-degree bend carries F_in = F_out exp(mu theta) = 1.602 N while the
    walls slide along the wire (t > 0.35 s), within 1 % (the membrane limit: the wire
    is stress free on the outer wall, so bending adds nothing)."""
    p = load_problem("contact_insertion", {"simulation.t_end": 0.5})
    res = simulate(p)
    assert res.status == "finished", res.message
    want = ref.insertion_force_capstan(1.0, mu=p.obstacles[0].friction,
                                       bend_angle=math.pi / 2)
    sliding = res.t > 0.38
    F = res.reactions["start"]["force"][2][sliding]
    assert np.all(np.abs(F / want - 1.0) < 1e-2)
    assert res.summary()["obstacles"][0]["force"]["max_norm"] > want


def test_kvrod_static_reports_what_the_table_carries(tmp_path):
    """kvrod static of the lifted rod: summary.json and static.npz give the table's force
    and moment (about its point) on the rod, which balance gravity and the lifting force:
    q L - F up, and the moments of the weight (trapezoidal over the equilibrium's nodes,
    as the rod lumps it) and of F about the table's point."""
    import json

    from runtime.io.runs import static_and_write

    p = load_problem("contact_lifted_rod")
    summary, model, y = static_and_write(p, tmp_path / "static")
    assert summary["status"] == "finished", summary["message"]
    r = dict(p.section.dims)["radius"]
    q = p.material.density * math.pi * r * r * 9.81
    F = p.loads[1].vector[2]
    table = summary["obstacles"][0]
    assert table["force"][2] == pytest.approx(q * p.rod.length - F, rel=1e-9)
    with np.load(tmp_path / "static" / "static.npz") as z:
        x = z["positions"] - np.asarray(p.obstacles[0].point)[:, None]
        assert np.allclose(z["obstacle0_force"], table["force"])
    w = np.full(x.shape[1], p.rod.length / p.rod.elements)
    w[[0, -1]] *= 0.5
    weight_moment = q * np.sum(w * x[0])                  # (r x (0, 0, -q ds))_y
    lift_moment = -x[0, -1] * F                            # (r x (0, 0, F))_y
    assert table["moment"][1] == pytest.approx(-(weight_moment + lift_moment), rel=1e-6)
    assert -0.1 * r < table["gap_min"] < 0.0
    on_disk = json.loads((tmp_path / "static" / "summary.json").read_text())
    assert on_disk["obstacles"][0]["force"] == table["force"]


def test_an_assemblys_run_folder_has_its_obstacles_series_and_contact_plot(draped_held,
                                                                         tmp_path):
    """series.npz holds obstacle{k}_* as a single rod's, summary.json the obstacle, and
    kvrod plot draws contact.png for an assembly too."""
    import json

    from runtime.io.assembly_plots import plot_assembly_run_folder
    from runtime.io.assembly_results import write_assembly_run

    _, res = draped_held
    write_assembly_run(tmp_path, res)
    with np.load(tmp_path / "series.npz") as z:
        assert z["obstacle0_force"].shape == (3, res.t.size)
        assert z["obstacle0_gap_min"].shape == (res.t.size,)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["obstacles"][0]["kind"] == "cylinder"
    paths = plot_assembly_run_folder(tmp_path)
    assert tmp_path / "contact.png" in paths and (tmp_path / "contact.png").stat().st_size

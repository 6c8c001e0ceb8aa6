"""The self-contact share measurement's rod is what it claims: a coil whose turns touch
(every segment has pairs in reach one turn up and down), and without ``contact`` it has
no self-contact at all; its README lines carry the measured numbers."""

from __future__ import annotations

from pathlib import Path

from bench import self_contact_share as scs


def test_the_coil_of_the_measurement_touches_itself_turn_on_turn(tmp_path: Path):
    from runtime.problem.assemble import build_model

    N = 200
    on = build_model(scs._load(scs.problem(N, 0.01, True), tmp_path))
    off = build_model(scs._load(scs.problem(N, 0.01, False), tmp_path))
    y = on.initial_state(0.0)
    values = on.self_contact_values(0.0, y)
    # 20 segments a turn: each one meets the turns above and below it
    assert values["pairs"] >= N - 2 * N / scs.TURNS
    assert 0.0 <= values["gap_min"] < 2e-5                    # 10 um apart, not inside
    assert off.self_contact is None


def test_the_readme_lines_give_the_share_and_the_whole_contact_cost():
    doc = {"N": 1000, "T": 0.02, "pairs_in_reach": 2000, "load_average_at_start": [1.0],
           "residual_on_s": 2e-3, "residual_off_s": 1e-4, "share_search_forces": 0.123,
           "share_all_contact": 0.6,
           "runs": {"on": {"steps": 10, "per_step": 0.05, "residuals": 30, "jacobians": 3,
                           "audit": 1e-6},
                    "off": {"steps": 12, "per_step": 0.02}}}
    text = " ".join(scs.markdown(doc))
    assert "12.3 % of a step" in text and "60 % of a step" in text
    assert scs.markdown({}) == []

"""Reproduction study: paper data, formula profiles, selection and tables (no runs)."""

import math

import pytest

from components.common.errors import ConfigError
from orchestrator.reproduce import (PAPER_SPEEDS, TABLES, check_selection, configuration,
                                    formula_profiles, load_paper_tables, mean_interval, plan)
from orchestrator.report.document import Document
from orchestrator.report.markdown import render_markdown
from orchestrator.reproduce.report import Table


def test_paper_tables_load_with_every_table_the_report_needs():
    paper = load_paper_tables()
    for name in ("table1_without_curvature", "table2_with_curvature", "table3_rmse",
                 "table6_static_profile", "table7_dynamic_profile",
                 "table8_curvature_tracking", "table9_rmse"):
        assert name in paper
    assert tuple(paper["table1_without_curvature"]["v"]) == PAPER_SPEEDS
    assert paper["table1_without_curvature"]["distance_m"][0] == 2.050
    assert paper["table9_rmse"]["rmse"] == [0.0213, 0.0019, 0.0392, 0.0072]


def test_paper_tables_bad_file_is_a_config_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[table1\n")
    with pytest.raises(ConfigError, match="bad.toml: not valid TOML"):
        load_paper_tables(bad)


def test_formula_profiles_reproduce_table6_with_the_040_track():
    case1 = formula_profiles(0.40)["case1"]
    # Eqs. (36), (41)-(42) by hand: R = 2 / (2 sin 45), v = 0.3 (1 +- 0.2 / R)
    radius = 2.0 / (2.0 * math.sin(math.pi / 4))
    assert case1["radius"] == pytest.approx(radius)
    assert case1["left_velocity"] == pytest.approx(0.3 * (1 + 0.2 / radius))
    assert case1["right_velocity"] == pytest.approx(0.3 * (1 - 0.2 / radius))
    assert case1["left_distance"] == pytest.approx((radius + 0.2) * math.pi / 2)
    segment2 = formula_profiles(0.40)["case2_segment2"]
    assert segment2["right_velocity"] == pytest.approx(0.384, abs=1e-3)


def test_selection_errors_name_the_value_and_the_choices():
    with pytest.raises(ConfigError, match=r"'table4' not known; valid choices: table1"):
        check_selection(["table4"], None)
    with pytest.raises(ConfigError, match=r"not among the paper's speeds; valid choices: 0.1"):
        check_selection(None, [0.25])
    selected, speeds = check_selection(None, (0.5, 0.1))
    assert selected == set(TABLES) and speeds == (0.1, 0.5)


def test_report_table_prints_estimates_beside_the_paper():
    table = Table("t", "T", [("v", "v", ".1f"), ("d", "d [m] sim", ".3f"),
                             ("d_paper", "paper", ".3f")],
                  rows=[{"v": 0.1, "d": mean_interval([1.9, 2.0, 2.1]), "d_paper": 2.05},
                        {"v": 0.2, "d": mean_interval([None, None]), "d_paper": 2.3}])
    document = Document("report")
    table.add_to(document.section(table.title))
    text = render_markdown(document)
    assert "| v | d [m] sim | paper |" in text
    # mean 2.0, s = 0.1, t(0.975, 2) = 4.3027: half width 0.248
    assert "| 0.1 | 2.000 [1.752, 2.248] | 2.050 |" in text
    assert "| 0.2 | - (2 missing) | 2.300 |" in text


def test_plan_runs_every_arm_condition_and_reading_as_data():
    from orchestrator.reproduce.experiments import sec62_cell, t89_cell

    experiments = plan(set(TABLES), PAPER_SPEEDS, pd_gains=(3.7, 1.2))
    cells = {c.name: c for e in experiments for c in e.cells}
    # Tables 1-3: 5 speeds x 2 modes; Tables 8-9: 2 cases x (4 arms x (2 feedforward + 4
    # frictions) + 2 CPID per-sample cells) + 2 track-0.40 cells; Sec. 6.2: 2 starts x 2
    # paths x 3 arms
    assert len(cells) == 10 + 2 * (4 * 6 + 2) + 2 + 12
    printed = cells[t89_cell("static", "fgs_pd_paper", "ff_on", "mu0.05")].parameters
    assert printed["controller_left.form"] == printed["controller_right.form"] == "paper"
    assert printed["controller_left.trim_ki"] == 0.0 and printed["plant.mu"] == 0.05
    assert printed["controller_left.feedforward"] is True
    assert cells[t89_cell("static", "fgs_pd_paper", "ff_off", "mu0.8")].parameters[
        "controller_right.feedforward"] is False
    # feedforward off runs at nominal friction only
    assert t89_cell("static", "fgs_pd_paper", "ff_off", "mu0.05") not in cells
    fixed = cells[t89_cell("dynamic", "pd_median", "ff_on", "mu0.8")].parameters
    assert (fixed["controller_left.mode"], fixed["controller_left.pd_kp"],
            fixed["controller_right.pd_kd"]) == ("pd", 3.7, 1.2)
    assert "plant.mu" not in fixed
    # CPID's printed ki read per second and per 20 ms sample
    assert cells[t89_cell("static", "cpid", "ff_on", "mu0.8")].parameters[
        "controller_left.pid_ki"] == 0.5
    assert cells[t89_cell("static", "cpid", "ff_on", "mu0.8", "per_sample")].parameters[
        "controller_left.pid_ki"] == pytest.approx(25.0)
    assert t89_cell("static", "fgs_pd", "ff_on", "mu0.8", "per_sample") not in cells
    for start, distance in (("start_1m", 1.0), ("start_3m", 3.0)):
        sec62 = next(e for e in experiments if e.name == f"sec6_2_{start}")
        # 45 deg to the right of the robot facing +y, at the start distance
        assert (sec62.parameters["source.x0"], sec62.parameters["source.y0"]) == \
            pytest.approx((distance * math.sin(math.pi / 4), distance * math.cos(math.pi / 4)))
        assert sec62.parameters["source.y0"] + sec62.parameters["source.length"] == \
            pytest.approx(6.0)
        assert sec62_cell("s_curve", start, "rotate_then_go", "fgs_pd") in cells
    assert len(plan({"table1"}, (0.3,))[0].cells) == 2


def test_configuration_states_the_verdict_deciding_assumptions():
    text = " ".join(configuration((3.7, 1.2)).values())
    for needed in ("feedforward", "Kp in [-4, -3]", "0.289", "0.05", "10 ms", "45 deg",
                   "kp 3.700, kd 1.200", "25 1/s", "1 m or 3 m"):
        assert needed in text, needed

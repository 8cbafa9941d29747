"""Reproduction study: paper data, formula profiles, selection and tables (no runs)."""

import math

import pytest

from components.common.errors import ConfigError
from orchestrator.reproduce import (PAPER_SPEEDS, TABLES, check_selection, formula_profiles,
                                    load_paper_tables, mean_interval)
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
    text = table.to_markdown()
    assert "| v | d [m] sim | paper |" in text
    # mean 2.0, s = 0.1, t(0.975, 2) = 4.3027: half width 0.248
    assert "| 0.1 | 2.000 [1.752, 2.248] | 2.050 |" in text
    assert "| 0.2 | - (2 missing) | 2.300 |" in text

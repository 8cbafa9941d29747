"""Sweep grids and --set parsing (no runs)."""

import pytest

from components.common.errors import ConfigError
from orchestrator.sweep import expand_grid, parse_assignment


@pytest.mark.parametrize("text, expected", [
    ("planner.v_cruise=0.2,0.3", ("planner.v_cruise", [0.2, 0.3])),
    ("planner.mode=curvature,pure_pursuit", ("planner.mode", ["curvature", "pure_pursuit"])),
    ("localizer.seed=3", ("localizer.seed", [3])),
    ("source.mute_at_end=false,true", ("source.mute_at_end", [False, True])),
], ids=["floats", "strings", "int", "bools"])
def test_assignments_parse_to_typed_values(text, expected):
    assert parse_assignment(text) == expected


@pytest.mark.parametrize("text", ["v_cruise=0.2", "planner.v_cruise", "planner.v_cruise="],
                         ids=["no-instance", "no-equals", "no-values"])
def test_bad_assignments_name_the_expected_form(text):
    with pytest.raises(ConfigError, match="expected instance.parameter=value"):
        parse_assignment(text)


def test_grid_is_the_full_product_times_seeds():
    runs = expand_grid({"a.x": [1, 2], "b.y": ["p", "q", "r"]}, seeds=[7, 8])
    assert len(runs) == 2 * 3 * 2
    assert ({"a.x": 2, "b.y": "q"}, 8) in runs
    assert expand_grid({}, seeds=[1]) == [({}, 1)]

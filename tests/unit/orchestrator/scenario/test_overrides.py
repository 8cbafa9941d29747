"""``--set`` and ``--stop-time``: parsed like TOML scalars, validated like the scenario file."""

import pytest

from components.common.errors import ConfigError
from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.scenario import apply_overrides, load_scenario, parse_override, parse_value


@pytest.fixture(scope="module")
def s_curve():
    return load_scenario(REPO_ROOT / "scenarios" / "s_curve.toml")


@pytest.mark.parametrize("text, expected", [
    ("0.25", 0.25), ("7", 7), ("true", True), ("False", False), ("straight", "straight"),
    ("1e-3", 0.001),
], ids=["float", "int", "true", "false-any-case", "text", "exponent"])
def test_values_read_like_toml_scalars(text, expected):
    value = parse_value(text)
    assert value == expected and type(value) is type(expected)


def test_a_set_word_without_equals_gets_the_spelling_that_works():
    # the usual slip: the space makes the shell pass the value as the next word
    with pytest.raises(ConfigError) as caught:
        parse_override("planner.v_cruise", stray="0.2,0.3")
    assert str(caught.value) == ("--set 'planner.v_cruise': no '='; write it as one word: "
                                 "--set planner.v_cruise=0.2,0.3")


@pytest.mark.parametrize("text, fragment", [
    ("v_cruise", "expected instance.parameter=value with no spaces"),
    ("planner.v_cruise=", "expected instance.parameter=value"),
    ("=0.2", "expected instance.parameter=value"),
    ("planner.v_cruise=0.2,0.3", "a run takes one value per parameter; to run several, "
                                 "use `sonotrack sweep --set planner.v_cruise=0.2,0.3`"),
], ids=["no-instance", "no-value", "no-key", "a-list"])
def test_malformed_set_words_are_one_line(text, fragment):
    with pytest.raises(ConfigError, match=None) as caught:
        parse_override(text)
    assert fragment in str(caught.value) and "\n" not in str(caught.value)


def test_stop_time_and_parameters_are_applied(s_curve):
    changed = apply_overrides(s_curve, 2.0, ["planner.v_cruise=0.2", "source.path=straight"])
    assert changed.stop_time == 2.0 and changed.step_count == 200
    assert changed.parameters["planner.v_cruise"] == 0.2
    assert changed.parameters["source.path"] == "straight"
    assert changed.parameters["planner.mode"] == s_curve.parameters["planner.mode"]  # kept
    assert apply_overrides(s_curve) is s_curve


@pytest.mark.parametrize("stop_time, settings, fragments", [
    (None, ["planner.v_cruse=0.2"], ["with --set: field 'parameters.planner.v_cruse'",
                                     "did you mean 'v_cruise'?"]),
    (None, ["planner.v_cruise=99.0"], ["planner.v_cruise = 99.0", "[0.001, 10.0]"]),
    (None, ["planner.v_cruise=fast"], ["'fast' is a string, expected a number"]),
    (0.005, [], ["with --stop-time: field 'stop_time'", "not an integer multiple"]),
    (None, ["planner.v_cruise=0.2", "planner.v_cruise=0.3"], ["given twice"]),
], ids=["unknown-parameter", "out-of-range", "wrong-type", "stop-time-off-grid", "twice"])
def test_changes_are_checked_like_the_scenario_file(s_curve, stop_time, settings, fragments):
    with pytest.raises(ConfigError) as caught:
        apply_overrides(s_curve, stop_time, settings)
    for fragment in fragments:
        assert fragment in str(caught.value)


def test_a_relative_csv_value_is_a_file_of_the_working_folder(s_curve, tmp_path,
                                                              monkeypatch):
    (tmp_path / "w.csv").write_text("x,y\n0,1\n1,2\n", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    changed = apply_overrides(s_curve, None, ["source.path=w.csv"])
    assert changed.parameters["source.path"] == str(tmp_path / "w.csv")

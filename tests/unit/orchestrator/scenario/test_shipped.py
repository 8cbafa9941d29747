"""Shipped scenarios by name, from any working folder."""

import os

import pytest

from components.common.errors import ConfigError
from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.scenario import find_scenario, shipped_scenarios


def test_every_toml_under_scenarios_is_listed_by_its_relative_name():
    folder = REPO_ROOT / "scenarios"
    found = {os.path.relpath(os.path.join(root, name), folder)[:-len(".toml")]
             for root, _, names in os.walk(folder) for name in names if name.endswith(".toml")}
    assert set(shipped_scenarios()) == found
    assert {"s_curve", "static_case1", "faults/low_snr"} <= found


@pytest.mark.parametrize("text, relative", [
    ("s_curve", "s_curve.toml"), ("s_curve.toml", "s_curve.toml"),
    ("scenarios/straight.toml", "straight.toml"), ("faults/low_snr", "faults/low_snr.toml"),
], ids=["name", "file-name", "repo-path", "subfolder"])
def test_a_name_finds_the_shipped_file_from_another_folder(text, relative, tmp_path,
                                                           monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert find_scenario(text) == REPO_ROOT / "scenarios" / relative


def test_a_file_in_the_working_folder_wins(tmp_path, monkeypatch):
    (tmp_path / "s_curve").write_text("", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert find_scenario("s_curve").resolve() == tmp_path / "s_curve"


def test_an_unknown_name_is_one_line_with_the_closest_and_the_list(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as caught:
        find_scenario("s_curv")
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith("scenario 's_curv' is neither a file nor a shipped scenario "
                              "(did you mean 's_curve'?); shipped scenarios: ")
    assert "static_case1" in message and "faults/mic_dead" in message


def test_a_folder_of_the_same_name_does_not_hide_the_shipped_scenario(tmp_path, monkeypatch):
    (tmp_path / "s_curve").mkdir()   # e.g. the output of an earlier `run --out s_curve`
    (tmp_path / "results").mkdir()
    monkeypatch.chdir(tmp_path)
    assert find_scenario("s_curve") == REPO_ROOT / "scenarios" / "s_curve.toml"
    assert find_scenario("results") == tmp_path.joinpath("results").relative_to(tmp_path)

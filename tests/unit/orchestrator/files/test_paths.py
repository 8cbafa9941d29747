"""Paths inside scenario and system files resolve from that file and stay in its folder."""

import os
from pathlib import Path

import pytest

from components.common.errors import ConfigError
from orchestrator.files.paths import confine, names_a_file
from orchestrator.scenario import load_scenario
from orchestrator.ssp import ComponentDescription, SystemDescription, read_ssd, ssd_to_string

REPO = Path(__file__).resolve().parents[4]
SSD = REPO / "fmus" / "SystemStructure.ssd"
WAYPOINTS = "x,y\n0.3,2.0\n0.8,3.0\n1.2,4.0\n"


def test_confine_resolves_inside_and_refuses_outside(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "w.csv").write_text(WAYPOINTS)
    (tmp_path / "w.csv").write_text(WAYPOINTS)
    assert confine("sub/w.csv", tmp_path) == ((tmp_path / "sub" / "w.csv").resolve(), None)
    path, problem = confine("../w.csv", tmp_path / "sub")
    assert path == (tmp_path / "w.csv").resolve() and "--allow-outside" in problem
    assert confine("../w.csv", tmp_path / "sub", allow_outside=True)[1] is None
    assert "leads outside" in confine("/etc/passwd", tmp_path)[1]
    (tmp_path / "sub" / "link.csv").symlink_to(tmp_path / "w.csv")
    assert "leads outside" in confine("link.csv", tmp_path / "sub")[1]
    assert "does not exist" in confine("missing.csv", tmp_path)[1]
    assert names_a_file("a/B.CSV") and not names_a_file("s_curve") and not names_a_file(1.0)


def _scenario(folder, path_value):
    folder.mkdir(parents=True, exist_ok=True)
    scenario = folder / "scenario.toml"
    scenario.write_text(f'stop_time = 1.0\nsystem = "{SSD}"\n[parameters]\n'
                        f'source.path = "{path_value}"\n')
    return scenario


def test_scenario_csv_resolves_from_the_scenario_not_the_working_folder(tmp_path, monkeypatch):
    scenario = _scenario(tmp_path / "scenarios", "paths/w.csv")
    (tmp_path / "scenarios" / "paths").mkdir()
    (tmp_path / "scenarios" / "paths" / "w.csv").write_text(WAYPOINTS)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    loaded = load_scenario(os.path.relpath(scenario, elsewhere))
    assert loaded.parameters["source.path"] == str(tmp_path / "scenarios" / "paths" / "w.csv")


def test_scenario_csv_outside_its_folder_needs_allow_outside(tmp_path):
    (tmp_path / "w.csv").write_text(WAYPOINTS)
    scenario = _scenario(tmp_path / "scenarios", "../w.csv")
    with pytest.raises(ConfigError) as raised:
        load_scenario(scenario)
    assert "parameters.source.path" in str(raised.value)
    assert "--allow-outside" in str(raised.value)
    loaded = load_scenario(scenario, allow_outside=True)
    assert loaded.parameters["source.path"] == str((tmp_path / "w.csv").resolve())


def _ssd_with_binding(folder, binding, name="s.ssd"):
    text = ssd_to_string(SystemDescription("s", [ComponentDescription("source", "S.fmu")]))
    text = text.replace('source="S.fmu"/>', 'source="S.fmu"><ssd:ParameterBindings>'
                        f'{binding}</ssd:ParameterBindings></ssd:Component>')
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _ssv(path, csv_value):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(
        '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
        ' version="1.0" name="v"><ssv:Parameters>'
        f'<ssv:Parameter name="path"><ssv:String value="{csv_value}"/></ssv:Parameter>'
        '</ssv:Parameters></ssv:ParameterSet>', encoding="utf-8")


def test_ssv_outside_the_ssd_folder_is_refused(tmp_path):
    system = tmp_path / "system"
    system.mkdir()
    _ssv(tmp_path / "values.ssv", "s_curve")
    ssd = _ssd_with_binding(system, '<ssd:ParameterBinding source="../values.ssv"/>')
    with pytest.raises(ConfigError, match="parameter file '../values.ssv' leads outside") as e:
        read_ssd(ssd)
    assert "--allow-outside" in str(e.value)
    passwd = _ssd_with_binding(system, '<ssd:ParameterBinding source="../../../../etc/passwd"/>',
                               "passwd.ssd")
    with pytest.raises(ConfigError, match="leads outside"):
        read_ssd(passwd)
    bound = read_ssd(ssd, allow_outside=True).components[0].parameters["path"]
    assert bound.run_value() == "s_curve"


def test_csv_in_an_ssv_resolves_from_the_ssv_folder(tmp_path):
    system = tmp_path / "system"
    _ssv(system / "values" / "v.ssv", "w.csv")
    (system / "values" / "w.csv").write_text(WAYPOINTS)
    ssd = _ssd_with_binding(system, '<ssd:ParameterBinding source="values/v.ssv"/>')
    bound = read_ssd(ssd).components[0].parameters["path"]
    assert bound.value == "w.csv"  # kept as written (a rewritten .ssd stays relative)
    assert bound.run_value() == str((system / "values" / "w.csv").resolve())


def test_csv_in_an_ssv_leading_outside_is_refused(tmp_path):
    system = tmp_path / "system"
    _ssv(system / "v.ssv", "../../w.csv")
    (tmp_path / "w.csv").write_text(WAYPOINTS)
    ssd = _ssd_with_binding(system, '<ssd:ParameterBinding source="v.ssv"/>')
    with pytest.raises(ConfigError, match=r"'\.\./\.\./w\.csv' leads outside"):
        read_ssd(ssd)


def test_scenario_check_of_its_system_honours_allow_outside(tmp_path):
    """The scenario loader reads the .ssd too: an .ssv outside it needs the same option."""
    system = tmp_path / "system"
    system.mkdir()
    _ssv(tmp_path / "values.ssv", "s_curve")
    ssd = _ssd_with_binding(system, '<ssd:ParameterBinding source="../values.ssv"/>')
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(f'stop_time = 1.0\nsystem = "{ssd}"\n')
    with pytest.raises(ConfigError, match="--allow-outside"):
        load_scenario(scenario)
    assert load_scenario(scenario, allow_outside=True).system == ssd.resolve()

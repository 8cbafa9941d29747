"""Fault schedules as data: the pure schedule type, the FMU parameter text, the scenario section."""

import math

import pytest

from components.common.errors import ConfigError, ParameterError
from components.common.faults import (KINDS, Fault, FaultSchedule, encode_schedule, kinds_of,
                                      parse_schedule)
from components.acoustics.faults import drops_fix
from orchestrator.scenario import scenario_from_dict

_BASE = {"stop_time": 1.0}


def test_active_on_half_open_interval():
    fault = Fault("mic_dead", 2.0, 4.0, channel="M1")
    assert [fault.active(t) for t in (1.999, 2.0, 3.0, 3.999, 4.0)] == [
        False, True, True, True, False]
    forever = Fault("mic_dead", 2.0, channel="M1")
    assert forever.permanent and forever.active(1e9)


def test_schedule_round_trips_through_the_fmu_parameter_text():
    faults = [Fault("mic_clipping", 1.0, 2.5, 0.05, "M3"), Fault("lost_fixes", 0.0, math.inf, 0.5),
              Fault("reflecting_wall", 3.0, 4.0, -1.25)]
    schedule = parse_schedule(encode_schedule(faults), "AcousticLocalizer")
    assert schedule.faults == tuple(faults)
    assert [f.kind for f in schedule.active(1.5)] == ["mic_clipping", "lost_fixes"]
    assert schedule.count_active(3.5) == 2
    assert not parse_schedule("", "AcousticLocalizer")


def test_every_kind_belongs_to_one_model():
    models = {"AcousticLocalizer", "SoundSource", "RobotPlant"}
    assert {kind.model for kind in KINDS.values()} == models
    assert set(kinds_of("SoundSource")) == {"source_silent"}


@pytest.mark.parametrize("text, words", [
    ('[{"kind":"mic_dead","start":0,"magnitude":0}]', ["fault_schedule[0].channel", "''",
                                                       "M1, M2, M3"]),
    ('[{"kind":"supply_sag","start":0}]', ["fault_schedule[0].kind", "mic_dead"]),
    ('[{"kind":"low_snr","start":5,"end":2}]', ["fault_schedule[0].end", "> start"]),
    ('[{"kind":"lost_fixes","start":0,"magnitude":1.5}]', ["magnitude", "0..1"]),
    ('{"kind":"lost_fixes"}', ["not a JSON list"]),
    ("not json", ["not JSON"]),
], ids=["no channel", "wrong model", "end before start", "magnitude range", "not a list",
        "not json"])
def test_bad_fmu_schedule_names_entry_field_and_choices(text, words):
    with pytest.raises(ParameterError) as caught:
        parse_schedule(text, "AcousticLocalizer")
    for word in words:
        assert word in str(caught.value)


def test_drops_fix_loses_exactly_the_fraction():
    assert [drops_fix(k, 0.5) for k in range(6)] == [False, True, False, True, False, True]
    assert sum(drops_fix(k, 0.3) for k in range(1000)) == 300
    assert not any(drops_fix(k, 0.0) for k in range(100))
    assert all(drops_fix(k, 1.0) for k in range(100))


def test_scenario_faults_are_checked_with_one_line_per_problem():
    data = dict(_BASE, faults=[
        {"kind": "mic_ded", "target": "localizer", "start": 1.0},
        {"kind": "low_friction", "target": "plant", "start": 0.0, "region": [1, 0, 0, 1]},
        {"kind": "encoder_freeze", "target": "plant", "start": -1.0, "channel": "middle"},
    ])
    with pytest.raises(ConfigError) as caught:
        scenario_from_dict(data, source="x.toml")
    lines = str(caught.value).splitlines()[1:]
    assert len(lines) == 4, lines
    assert "x.toml: field 'faults[0].kind': 'mic_ded' is not one of mic_dead" in lines[0]
    assert "faults[1].region" in lines[1]
    assert "faults[2].start" in lines[2]
    assert "faults[2].channel" in lines[3] and "left, right, both" in lines[3]


def test_scenario_faults_survive_to_dict_and_back():
    scenario = scenario_from_dict(dict(_BASE, faults=[
        {"kind": "source_silent", "target": "source", "start": 0.2, "end": 0.5},
        {"kind": "mic_dead", "target": "localizer", "start": 0.1, "channel": "M2"}]))
    again = scenario_from_dict(scenario.to_dict())
    assert again.faults == scenario.faults
    assert again.input_hash() == scenario.input_hash()
    # a scenario without faults hashes as before the section existed: no "faults" key
    assert "faults" not in scenario_from_dict(dict(_BASE)).to_dict()
    assert scenario.input_hash() != scenario_from_dict(dict(_BASE)).input_hash()


def test_fault_schedule_is_empty_by_default():
    assert len(FaultSchedule()) == 0 and not FaultSchedule()

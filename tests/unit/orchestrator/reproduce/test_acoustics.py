"""The room condition of the reproduction study: it reaches the localizer, and the room holds
every fix-dependent experiment (no runs)."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from components.common.errors import ConfigError
from components.source.paths import SCurvePath
from orchestrator.reproduce import PAPER_SPEEDS, TABLES, load_tolerances, plan
from orchestrator.reproduce.acoustics import Room, check_room_fits, load_room, room_problems

ROOM_TOML = Path(__file__).resolve().parents[4] / "scenarios" / "room.toml"
# The experiments whose claims rest on the fixes (issue 22, item 4), and nothing else.
ROOM_EXPERIMENTS = ({f"table13_v{v:g}_room" for v in PAPER_SPEEDS}
                    | {"sec6_2_start_1m_room", "sec6_2_start_3m_room"})


def _room_file():
    """scenarios/room.toml's localizer settings and box, read here without the study's code."""
    table = tomllib.loads(ROOM_TOML.read_text())["parameters"]
    localizer = {f"localizer.{k}": v for k, v in table["localizer"].items()}
    x0, y0 = localizer["localizer.room_origin_x"], localizer["localizer.room_origin_y"]
    box = (x0, x0 + localizer["localizer.room_length_x"],
           y0, y0 + localizer["localizer.room_length_y"])
    return localizer, box


@pytest.fixture(scope="module")
def experiments():
    return plan(set(TABLES), PAPER_SPEEDS, room=load_room())


def test_the_room_reaches_the_localizer_of_every_fix_dependent_cell(experiments):
    localizer, _ = _room_file()
    assert localizer["localizer.room"] is True and len(localizer) >= 10
    in_room = [e for e in experiments if e.name.endswith("_room")]
    assert {e.name for e in in_room} == ROOM_EXPERIMENTS
    free = {e.name: e for e in experiments if not e.name.endswith("_room")}
    for experiment in in_room:
        twin = free[experiment.name.removesuffix("_room")]
        base = experiment.base_scenario().parameters
        assert [c.name for c in experiment.cells] == [c.name for c in twin.cells]
        for cell, twin_cell in zip(experiment.cells, twin.cells):
            # what a run of the cell is given: the experiment's scenario, then the cell's own
            run = {**base, **cell.parameters}
            assert {k: run.get(k) for k in localizer} == localizer, cell.name
            assert run["source.emit_period"] == run["localizer.burst_period"]
            free_run = {**twin.base_scenario().parameters, **twin_cell.parameters}
            assert not free_run.get("localizer.room", False), twin_cell.name
            # nothing but the room differs between the twins
            assert ({k: v for k, v in run.items() if k not in localizer}
                    == {k: v for k, v in free_run.items() if not k.startswith("localizer.")}
                    | {"source.emit_period": 0.01})
    # the Monte Carlo draws vary no room setting
    assert not {t.parameter for t in load_tolerances()} & set(localizer)


def test_the_room_holds_every_fix_dependent_experiment_exactly(experiments):
    _, (x_min, x_max, y_min, y_max) = _room_file()
    assert (x_min, x_max, y_min, y_max) == (-3.5, 3.5, -0.5, 6.5)

    def inside(x, y):
        return min(np.min(x - x_min), np.min(x_max - x), np.min(y - y_min), np.min(y_max - y))

    # The paper's geometry: robot at (0, 0) facing +y, microphones 0.4 m apart (Table 11), so
    # within 0.4 m of the centre at any heading; Sec. 3.6's source at (1.5, 1.5); Sec. 6.2's
    # starting 1 m away at 45 deg right, driving +y to y = 6 (0.5 m short of the far wall),
    # the S-curve w(u) = A 16/(3 sqrt 3) sin^3 cos with A = 0.5 m.
    angle = np.linspace(0.0, 2.0 * math.pi, 3601)
    microphones = inside(0.4 * np.cos(angle), 0.4 * np.sin(angle))
    assert microphones == pytest.approx(0.1)
    assert inside(np.array([1.5]), np.array([1.5])) == pytest.approx(2.0)
    x0 = y0 = math.sqrt(0.5)
    length = 6.0 - y0
    u = np.linspace(0.0, length, 200001)
    phase = np.pi * u / length
    w = 0.5 * 16.0 / (3.0 * math.sqrt(3.0)) * np.sin(phase) ** 3 * np.cos(phase)
    assert inside(x0 - w, y0 + u) == pytest.approx(0.5)
    assert np.max(np.abs(w)) == pytest.approx(0.5, abs=1e-9)
    sec62 = next(e for e in experiments if e.name == "sec6_2_start_1m_room")
    assert sec62.parameters["source.length"] == pytest.approx(length, abs=1e-12)
    # the source's own path code ends where the geometry says
    end = SCurvePath(x0, y0, 0.5 * math.pi, sec62.parameters["source.length"], 0.5)
    assert end.position(end.length) == pytest.approx((x0, 6.0), abs=1e-9)

    problems, clearance = room_problems(
        [e for e in experiments if e.name.endswith("_room")], load_room())
    assert problems == []
    assert clearance == pytest.approx({name: 0.1 for name in ROOM_EXPERIMENTS})


def test_a_room_that_misses_the_start_is_refused_naming_the_point(experiments):
    room = load_room()
    moved = Room({**room.parameters, "localizer.room_origin_y": 0.0}, room.source)
    in_room = [e for e in experiments if e.name.endswith("_room")]
    with pytest.raises(ConfigError) as error:
        check_room_fits(in_room, moved)
    lines = str(error.value).splitlines()[1:]
    # two microphone corners below y = 0 for each of the seven experiments, nothing else
    assert len(lines) == 14
    assert all("microphones at the start at (" in line and "-0.4) m is outside the room "
               "(x in [-3.5, 3.5], y in [0, 7] m, scenarios/room.toml)" in line
               for line in lines)


def test_a_scenario_without_the_room_is_refused(tmp_path):
    free = tmp_path / "free.toml"
    free.write_text('[parameters]\nlocalizer.room = false\n')
    with pytest.raises(ConfigError, match="localizer.room = False; the room condition needs"):
        load_room(free)

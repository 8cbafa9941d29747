"""The minimum settling time any controller can reach, against the first-order formula and
against real controllers (none beats it; one that knows the wheel meets it)."""

import math

import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from orchestrator.verify.checks import load_requirements
from orchestrator.verify.loop_model import linear_wheel_model
from orchestrator.verify.requirement_runs import run_model_experiment
from orchestrator.verify.settling_bound import minimum_settling_time

PLANT = PlantParameters()
REQ = load_requirements()
CELLS = [(0.25, 2.0), (0.25, 0.2), (1.0, 1.0), (4.0, 0.2), (0.5, 2.0)]


def _first_order(model, speed, band, supply):
    gain, tau = model.dc_gain, model.time_constants[1]
    return -tau * math.log(1.0 - speed * (1.0 - band) / (gain * supply))


@pytest.mark.parametrize("cell", CELLS, ids=[f"x{g:g}-tau-x{t:g}" for g, t in CELLS])
def test_bound_is_the_first_order_reach_time_plus_the_armature_millisecond(cell):
    model = linear_wheel_model(PLANT).scaled(*cell)
    bound = minimum_settling_time(model, 0.3, 0.02, PLANT.v_supply)
    first_order = _first_order(model, 0.3, 0.02, PLANT.v_supply)
    assert first_order < bound < first_order + 1.5e-3


def test_the_worst_corner_of_the_grid_needs_half_a_second():
    model = linear_wheel_model(PLANT).scaled(0.25, 2.0)
    assert minimum_settling_time(model, 0.3, 0.02, PLANT.v_supply, 0.02) == pytest.approx(0.50)


def test_a_wheel_too_weak_for_the_target_has_no_bound():
    model = linear_wheel_model(PLANT).scaled(0.01, 1.0)       # 0.025 m/s at full supply
    assert minimum_settling_time(model, 0.3, 0.02, PLANT.v_supply) == math.inf


@pytest.mark.parametrize("cell", CELLS, ids=[f"x{g:g}-tau-x{t:g}" for g, t in CELLS])
def test_no_controller_beats_the_bound_and_one_that_knows_the_wheel_meets_it(cell):
    grid = REQ["off_nominal_grid"]
    model = linear_wheel_model(PLANT).scaled(*cell)
    bound = minimum_settling_time(model, 0.3, 0.02, PLANT.v_supply, PLANT.speed_window)
    for settings in (dict(DEFAULTS), dict(DEFAULTS, form="paper"), dict(DEFAULTS, mode="pid")):
        value = run_model_experiment("off_nominal_settling", settings, PLANT, cell, REQ, grid)
        assert value["value"] >= bound - 1e-9
    knows = dict(DEFAULTS, volts_per_speed=1.0 / model.dc_gain,
                 acceleration_feedforward=model.time_constants[1])
    value = run_model_experiment("off_nominal_settling", knows, PLANT, cell, REQ, grid)["value"]
    # full voltage, then the steady voltage: within one 20 ms window past the continuous
    # bound on the slow wheels; the fast ones (tau_m 77 ms) need up to 0.12 s
    assert value <= max(bound + 0.02, 0.12) + 1e-9

"""Each off-nominal requirement holds for the default form and fails on a broken controller.

On the discrete-time loop (the real controller on the sampled wheel; the RobotPlant core for
slip), one or two wheels each: the whole grid runs in `sonotrack verify`. The broken ones are
the issue's: the paper form's slow trim (settling, load, ramp lag), no reset at a stop
(creep), an undamped PD (limit cycle and slip chatter).
"""

import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from orchestrator.verify.checks import load_requirements
from orchestrator.verify.designs import design_settings
from orchestrator.verify.requirement_runs import run_model_experiment

REQ = load_requirements()
PLANT = PlantParameters()
DEFAULT = design_settings(dict(DEFAULTS), "default")
PAPER = design_settings(dict(DEFAULTS), "paper")
UNDAMPED_PD = dict(DEFAULT, mode="pd", pd_kp=14.0, pd_kd=0.0)


def _run(name, settings, cell, frictions=None):
    grid = dict(REQ["off_nominal_grid"])
    if frictions is not None:
        grid["frictions"] = frictions
    return run_model_experiment(name, settings, PLANT, cell, REQ, grid)


def test_settling_within_1_s_at_half_the_gain_and_the_old_trim_misses_it():
    assert _run("off_nominal_settling", DEFAULT, (0.5, 1.0)) == pytest.approx(
        {"value": 0.80, "passed": True}, abs=0.03)
    for cell in ((0.5, 1.0), (0.25, 1.0)):
        result = _run("off_nominal_settling", PAPER, cell)
        assert not result["passed"] and result["value"] > 1.0


def test_load_step_recovered_within_1_s_and_the_old_trim_never_recovers():
    result = _run("load_step_recovery", DEFAULT, (1.0, 1.0))
    assert result["passed"] and result["value"] < 1.0
    # 20 % of RobotPlant's stall force at 11.1 V, K_f 11.1 / R
    assert result["load_force_n"] == pytest.approx(0.2 * 3.375 * 11.1 / 2.4, rel=1e-3)
    assert not _run("load_step_recovery", PAPER, (1.0, 1.0))["passed"]


def test_ramp_lag_below_one_fix_period_and_the_paper_form_lags_more_on_a_weak_wheel():
    bound = REQ["ramp_lag"]["acceleration_m_s2"] * REQ["ramp_lag"]["fix_period_s"]
    assert bound == pytest.approx(0.04)
    good = _run("ramp_lag", DEFAULT, (0.5, 1.0))
    bad = _run("ramp_lag", PAPER, (0.5, 1.0))
    assert good["passed"] and good["value"] < bound < bad["value"] and not bad["passed"]


def test_no_creep_with_the_reset_and_creep_without_it():
    cell = (0.25, 2.0)   # a slow wheel needing four times the voltage: a large held integral
    assert _run("no_creep", DEFAULT, cell)["passed"]
    broken = _run("no_creep", dict(DEFAULT, zero_reference_reset=False), cell)
    assert not broken["passed"] and broken["value"] > REQ["no_creep"]["max_creep_m"]


def test_no_limit_cycle_for_the_default_and_an_undamped_pd_limit_cycles():
    good = _run("no_limit_cycle", DEFAULT, (1.0, 1.0))
    assert good["passed"] and good["value"] < 0.5
    bad = _run("no_limit_cycle", UNDAMPED_PD, (1.0, 1.0))
    assert not bad["passed"] and bad["value"] > 1.2


def test_slip_chatter_flips_with_an_undamped_pd_at_friction_02():
    good = _run("no_slip_chatter", DEFAULT, (1.0, 1.0), frictions=[0.2])
    assert good["passed"] and good["value"] == 0
    bad = _run("no_slip_chatter", UNDAMPED_PD, (1.0, 1.0), frictions=[0.2])
    assert not bad["passed"] and bad["value"] > REQ["no_slip_chatter"]["max_entries_per_second"]


def test_the_default_form_slides_repeatedly_at_friction_005():
    # the measured limit (docs/control.md): at mu 0.05 the planner's ramp uses 82 % of the
    # friction and the encoder's one-count voltage steps push the tyre past it
    result = _run("no_slip_chatter", DEFAULT, (1.0, 1.0), frictions=[0.05])
    assert not result["passed"] and result["at_friction"] == 0.05

"""Verdicts of the off-nominal requirements, their ranges, and the designs judged."""

import math

import pytest

from components.control import DEFAULTS, WheelSpeedController
from orchestrator.verify.checks import load_requirements
from orchestrator.verify.designs import design_settings, loop_gains
from orchestrator.verify.requirement_checks import (
    check_requirement, design_lines, largest_ranges, requirement_checks,
)
from orchestrator.verify.wheel_experiments import REQUIREMENTS, judged_cells

REQ = load_requirements()
GRID = REQ["off_nominal_grid"]
GAINS, TAUS = GRID["gain_factors"], GRID["time_constant_factors"]


def _rows(passes):
    """Rows of the grid, ``passes(g, t)`` deciding each cell; value 1 if it holds, else 2."""
    return [{"gain_factor": g, "time_constant_factor": t, "passed": passes(g, t),
             "value": 1.0 if passes(g, t) else 2.0} for g in GAINS for t in TAUS]


def test_largest_ranges_of_a_known_map():
    # holds where gain <= 2 and tau >= 0.5, except the one cell (2, 2)
    rows = _rows(lambda g, t: g <= 2 and t >= 0.5 and (g, t) != (2.0, 2.0))
    ranges = largest_ranges(rows, GAINS, TAUS)
    assert ranges["gain_at_tau_1"] == (0.25, 2.0)
    assert ranges["tau_at_gain_1"] == (0.5, 2.0)
    # candidates: gain 0.25..1 by tau 0.5..2 (9 cells) beats gain 0.25..2 by tau 0.5..1 (8)
    assert ranges["box"] == [0.25, 1.0, 0.5, 2.0]
    assert (ranges["passing"], ranges["cells"]) == (11, 20)


def test_no_range_when_the_nominal_wheel_fails():
    ranges = largest_ranges(_rows(lambda g, t: (g, t) != (1.0, 1.0)), GAINS, TAUS)
    assert ranges["box"] is None and ranges["gain_at_tau_1"] is None


def test_ranges_in_words_when_the_nominal_wheel_fails_or_holds():
    table, judged = REQ["off_nominal_settling"], judged_cells(GRID)
    failing = check_requirement("off_nominal_settling", "default",
                                _rows(lambda g, t: (g, t) != (1.0, 1.0)), None, GRID, table,
                                judged)
    assert "it fails on RobotPlant's own wheel (19 of 20 wheels pass)." in failing.measured
    assert "holds for not at" not in failing.measured
    holding = check_requirement("off_nominal_settling", "default", _rows(lambda g, t: g <= 2),
                                None, GRID, table, judged)
    assert ("it holds for gain x0.25..x2 at tau x1 and tau x0.2..x2 at gain x1; largest box "
            "gain x0.25..x2 by tau x0.2..x2 (16 of 20 wheels pass)") in holding.measured


def test_verdict_is_on_the_judged_cells_and_the_fmus():
    # the rule that judges only part of the grid (the shipped file judges all of it)
    grid = dict(GRID, judged_factor_span=2.0)
    judged = judged_cells(grid)
    assert len(judged) == 7 and len(judged_cells(GRID)) == 20
    everywhere = _rows(lambda g, t: True)
    on_judged_only = _rows(lambda g, t: (g, t) in judged)
    table = REQ["off_nominal_settling"]
    assert check_requirement("off_nominal_settling", "default", on_judged_only, None, grid, table,
                             judged).passed
    one_out = _rows(lambda g, t: (g, t) != (2.0, 2.0))
    check = check_requirement("off_nominal_settling", "default", one_out, None, grid, table, judged)
    assert not check.passed and check.verdict == "FAIL"
    assert "1 of 7 judged wheels fail" in check.measured
    assert "gain, time constant and gain/tau lie within x0.5..x2" in check.requirement
    fmu_fails = [dict(r, passed=r["gain_factor"] != 0.5) for r in everywhere if
                 (r["gain_factor"], r["time_constant_factor"]) in judged]
    check = check_requirement("off_nominal_settling", "paper", everywhere, fmu_fails, grid,
                              table, judged)
    assert not check.passed and check.verdict == "warning"   # the paper's design: a finding


def test_design_lines_say_what_each_design_meets():
    judged = judged_cells(GRID)
    model = {design: {name: _rows(lambda g, t: design == "default" or name == "no_creep")
                      for name in REQUIREMENTS} for design in ("default", "paper", "pid")}
    checks = requirement_checks({"model": model, "fmu": {}, "judged": judged}, REQ)
    assert len(checks) == 18 and checks[0].name == "off_nominal_settling_default"
    lines = design_lines(checks)
    assert lines[0] == ("FGS-PD, default form: meets settling, load recovery, ramp lag, creep, "
                        "limit cycle, slip chatter (all six).")
    assert lines[1].startswith("FGS-PD, paper form: meets creep; fails settling, load recovery")
    assert "the FMUs were not run" in checks[0].measured


def test_each_design_builds_and_reads_only_its_forms_parameters():
    settings = dict(DEFAULTS, integral_gain=10.0)
    paper = design_settings(settings, "paper")
    assert paper["form"] == "paper" and paper["integral_gain"] == DEFAULTS["integral_gain"]
    WheelSpeedController(**paper)   # refused if a default-form parameter were left changed
    assert design_settings(settings, "default")["integral_gain"] == 10.0
    assert design_settings(settings, "pid")["mode"] == "pid"
    with pytest.raises(Exception, match="design 'x'"):
        design_settings(settings, "x")


def test_loop_gains_scale_the_default_form_and_keep_the_papers():
    default = design_settings(dict(DEFAULTS), "default")
    kp, kd, ki = loop_gains(default, 4.0, 2.0)
    assert kp == pytest.approx(4.0 * DEFAULTS["gain_scale"])
    assert kd * DEFAULTS["e_range"] / DEFAULTS["de_range"] == pytest.approx(
        2.0 * DEFAULTS["gain_scale"] * DEFAULTS["derivative_time"])
    assert ki == DEFAULTS["integral_gain"]
    assert loop_gains(design_settings(dict(DEFAULTS), "paper"), 4.0, 2.0) == (
        4.0, 2.0, DEFAULTS["trim_ki"])
    assert not math.isnan(kp)

"""Every check of `sonotrack verify` passes on the real loop and fails on a broken one.

Each broken case is a real computation on a deliberately wrong input (gains beyond the edge,
a plant with another resistance, a controller with another gain, the trim switched off), not
an edited verdict; the FMU checks' flips are in tests/integration/orchestrator/verify/test_report.py.
The checks are exercised on the paper form, whose numbers docs/verification.md quotes; the
default form's are in test_requirement_checks.py and test_designs.py.
"""


import copy
import json
from pathlib import Path

import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from orchestrator.verify import WheelLoopModel, controller_cross_check, load_requirements, verify
from orchestrator.verify import checks as C
from orchestrator.verify import robust_checks as R
from orchestrator.verify import measure
from orchestrator.verify.designs import design_settings
from orchestrator.verify.report import _model_figures

REQ = load_requirements()


@pytest.fixture(scope="module")
def model():
    return WheelLoopModel()


@pytest.fixture(scope="module")
def surface(model):
    return measure.gain_surface(model, _settings(), 3)


def _settings(**changes):
    return dict(design_settings(dict(DEFAULTS), "paper"), **changes)


def test_requirements_file_states_every_threshold_with_a_reason():
    for name, table in REQ.items():
        assert len(table["why"].split()) >= 15, name
    assert REQ["routh_gives_paper_bounds"]["severity"] == "finding"


def test_routh_vs_roots_passes_and_flips_on_a_disagreement(surface):
    assert C.check_routh_vs_roots(surface, REQ["routh_vs_roots"]).passed
    broken = copy.deepcopy(surface)
    broken["grid"][0]["stable_routh"] = not broken["grid"][0]["stable_roots"]
    assert not C.check_routh_vs_roots(broken, REQ["routh_vs_roots"]).passed
    broken = copy.deepcopy(surface)
    broken["boundaries"][0]["relative_difference"] = 1e-3
    assert not C.check_routh_vs_roots(broken, REQ["routh_vs_roots"]).passed


def test_surface_stable_flips_with_gains_beyond_the_edge(model):
    good = _settings()
    distances = measure.surface_distances(model, measure.reachable_gains(good, 11), good)
    check = C.check_surface_stable(distances, REQ["surface_stable"])
    assert check.passed and check.values["min_edge_ratio"] > 8  # edge near kp 34 at kd 2
    beyond = _settings(kp_max=40.0)
    distances = measure.surface_distances(model, measure.reachable_gains(beyond, 11), beyond)
    check = C.check_surface_stable(distances, REQ["surface_stable"])
    assert not check.passed and distances["unstable"] > 0
    near = _settings(kp_min=20.0, kp_max=25.0)  # stable, but closer than 2x to the edge
    distances = measure.surface_distances(model, measure.reachable_gains(near, 11), near)
    assert distances["unstable"] == 0
    assert not C.check_surface_stable(distances, REQ["surface_stable"]).passed


def test_margins_and_steps_flip_near_the_edge(model, surface):
    for check in (C.check_gain_margin, C.check_phase_margin, C.check_step_response):
        assert check(surface, REQ[check.__name__[6:]]).passed, check.__name__
    near = measure.gain_surface(model, _settings(kp_min=28.0, kp_max=33.0), 2)
    assert not C.check_gain_margin(near, REQ["gain_margin"]).passed
    assert not C.check_phase_margin(near, REQ["phase_margin"]).passed
    assert not C.check_step_response(near, REQ["step_response"]).passed
    slow = measure.gain_surface(model, _settings(kp_min=0.05, kp_max=0.1, trim_ki=0.0), 2)
    check = C.check_step_response(slow, REQ["step_response"])
    assert not check.passed and check.values["settling_max_s"] > 0.5


def test_pid_baseline_flips_with_a_large_integral_gain(model):
    args = (REQ["pid_baseline"], (REQ["gain_margin"], REQ["phase_margin"]),
            REQ["step_response"])
    assert C.check_pid_baseline(measure.pid_baseline(model, _settings()), *args).passed
    wild = measure.pid_baseline(model, _settings(pid_ki=40.0))
    assert not C.check_pid_baseline(wild, *args).passed


def test_dc_gain_flips_for_a_plant_with_another_resistance(model):
    plant = PlantParameters()
    assert C.check_dc_gain(_model_figures(model, plant), REQ["dc_gain"]).passed
    other = PlantParameters(motor_resistance=1.5 * plant.motor_resistance)
    assert not C.check_dc_gain(_model_figures(model, other), REQ["dc_gain"]).passed


def test_controller_core_check_flips_for_a_controller_with_another_gain(model):
    good = measure.core_cross_check(model, _settings())
    assert C.check_controller_core_vs_tf(good, REQ["controller_core_vs_tf"]).passed
    bad = dict(good, pd_mid=controller_cross_check(model, 3.5, 1.15, 1.0,
                                                   controller_overrides={"pd_kp": 4.0}))
    assert not C.check_controller_core_vs_tf(bad, REQ["controller_core_vs_tf"]).passed


def test_paper_box_is_stable_on_our_signs_and_a_box_past_the_edge_fails(model):
    box = measure.paper_box(model, _settings(trim_ki=1.0))
    check = C.check_paper_gain_box(box, REQ["paper_gain_box"])
    assert check.passed and box["box"] == {"kp_min": 3.0, "kp_max": 4.0, "kd_min": 0.3,
                                           "kd_max": 2.0}
    # Read literally (the paper's negative gains on e = r - y) the loop is unstable.
    assert box["literal_signs_spectral_radius"] > 1.0
    far = measure.paper_box(model, _settings(trim_ki=1.0), box={
        "kp_min": 30.0, "kp_max": 40.0, "kd_min": 0.3, "kd_max": 2.0}, points=3)
    assert not C.check_paper_gain_box(far, REQ["paper_gain_box"]).passed


GRID = ([0.25, 0.5, 1.0, 2.0, 4.0], [0.5, 1.0, 2.0])


@pytest.fixture(scope="module")
def robust(model):
    settings = _settings()
    return (measure.robustness(model, settings, *GRID),
            measure.gain_factor_edges(model, settings, GRID[1]))


def test_robust_stability_requirement_is_the_gain_margins_6_db():
    # The two requirements state one margin: a plant-gain factor G is the controller scaled
    # by G, so robust_stability may not ask more (or less) than gain_margin does.
    assert max(REQ["robust_stability"]["gain_factors"]) == REQ["gain_margin"]["min_gain_margin"]
    assert REQ["robust_stability_x4"]["severity"] == "finding"
    assert REQ["robust_stability_x4"]["gain_factors"] == [4.0]


def test_robustness_with_the_trim_has_zero_steady_state_error(robust):
    r, _ = robust
    for name in ("fgs_pd", "pd", "pid"):
        check = R.check_robust_steady_state(r["points"][name], name, REQ["robust_steady_state"])
        assert check.passed, check.measured
        assert check.values["worst_fraction"] < 1e-6  # exactly 0 up to rounding (integral)


def test_robust_stability_passes_to_x2_and_x4_is_a_finding_for_the_paper_box(robust):
    r, edges = robust
    for name in ("fgs_pd", "pd", "pid"):
        check = R.check_robust_stability(r["points"][name], edges, name, REQ["robust_stability"])
        assert check.passed, check.measured
        assert check.values["points"] == 12 and check.values["at_time_constant_factor"] == 0.5
    worst = R.check_robust_stability(r["points"]["fgs_pd"], edges, "fgs_pd",
                                     REQ["robust_stability"]).values
    assert 2.0 < worst["largest_stable_gain_factor"] < 4.0  # 2.61 at (kp 4, kd 2)
    for name, radius in (("fgs_pd", "1.238"), ("pd", "1.064")):
        finding = R.check_robust_stability_beyond(r["points"][name], edges, name,
                                                  REQ["robust_stability_x4"])
        assert not finding.passed and finding.verdict == "warning"
        assert ("UNSTABLE on a wheel with 4x the DC gain and half the time constant; retune "
                "for such a motor") in finding.measured
        assert f"gain x4, tau x0.5: max|z| {radius}" in finding.measured
        assert finding.values["largest_stable_gain_factor"]["0.5"] < 4.0
    pid = R.check_robust_stability_beyond(r["points"]["pid"], edges, "pid",
                                          REQ["robust_stability_x4"])
    assert pid.passed and pid.values["largest_stable_gain_factor"]["0.5"] > 4.0


def test_robust_stability_fails_for_a_gain_set_unstable_inside_x2(model):
    # kd 5 on the fixed PD: stable on RobotPlant, stable only up to x1.6 at tau x0.5.
    settings = _settings(pd_kd=5.0)
    r = measure.robustness(model, settings, *GRID, controllers=("pd",))
    edges = measure.gain_factor_edges(model, settings, GRID[1], controllers=("pd",))
    check = R.check_robust_stability(r["points"]["pd"], edges, "pd", REQ["robust_stability"])
    assert not check.passed and "gain x2, tau x0.5" in check.measured
    assert check.values["largest_stable_gain_factor"] < 2.0


def test_robust_stability_fails_when_the_requirement_asks_more_or_the_edge_is_short(robust):
    r, edges = robust
    # x3 is not on the evaluated grid: the exact edge (2.61 at tau x0.5) still catches it.
    more = dict(REQ["robust_stability"], gain_factors=[0.25, 0.5, 1.0, 2.0, 3.0])
    assert not R.check_robust_stability(r["points"]["fgs_pd"], edges, "fgs_pd", more).passed
    assert R.check_robust_stability(r["points"]["pid"], edges, "pid", more).passed  # 4.10
    # An edge below x2 between the grid's points fails although every grid point is stable.
    short = copy.deepcopy(edges)
    short["sets"][-1]["edges"][1]["upper"] = 1.9
    assert not R.check_robust_stability(r["points"]["pid"], short, "pid",
                                        REQ["robust_stability"]).passed


def test_x4_finding_flips_for_a_stronger_pid_and_clears_when_the_controller_is_retuned(model):
    strong = _settings(pid_kd=2.0)
    r = measure.robustness(model, strong, [4.0], [0.5], controllers=("pid",))
    edges = measure.gain_factor_edges(model, strong, [0.5], controllers=("pid",))
    req = dict(REQ["robust_stability_x4"], time_constant_factors=[0.5])
    assert not R.check_robust_stability_beyond(r["points"]["pid"], edges, "pid", req).passed
    # Retuned for a motor with 4x the DC gain: volts_per_speed a quarter, the same loop again.
    settings = _settings(volts_per_speed=DEFAULTS["volts_per_speed"] / 4)
    retuned = WheelLoopModel(volts_per_speed=settings["volts_per_speed"])
    r = measure.robustness(retuned, settings, [4.0], [0.5], controllers=("fgs_pd",))
    edges = measure.gain_factor_edges(retuned, settings, [0.5], controllers=("fgs_pd",))
    check = R.check_robust_stability_beyond(r["points"]["fgs_pd"], edges, "fgs_pd", req)
    assert check.passed
    assert check.values["largest_stable_gain_factor"]["0.5"] == pytest.approx(4 * 2.6117,
                                                                              rel=1e-3)


def test_robust_steady_state_flips_without_the_trim_and_matches_the_analytic_value(model):
    pure = measure.robustness(model, _settings(trim_ki=0.0), [0.25], [1.0],
                              controllers=("pd",))["points"]["pd"][0]
    # Pure PD with feedforward on a wheel needing 4x the voltage: e_ss = 1 - a (1 + kp) /
    # (1 + a kp), a = 0.25, kp = pd_kp (derivative has no DC gain).
    a, kp = 0.25, DEFAULTS["pd_kp"]
    assert pure["steady_state_error"] == pytest.approx(1 - a * (1 + kp) / (1 + a * kp),
                                                       rel=1e-9)
    check = R.check_robust_steady_state([pure], "pd", REQ["robust_steady_state"])
    assert not check.passed
    no_integral = measure.robustness(model, _settings(pid_ki=0.0), [0.25], [1.0],
                                     controllers=("pid",))["points"]["pid"]
    assert not R.check_robust_steady_state(no_integral, "pid", REQ["robust_steady_state"]).passed


def test_robust_stability_flips_for_the_pid_with_gains_past_the_edge(model):
    wild = _settings(pid_kp=30.0)
    r = measure.robustness(model, wild, [1.0, 2.0], [1.0], controllers=("pid",))
    edges = measure.gain_factor_edges(model, wild, [1.0], controllers=("pid",))
    req = dict(REQ["robust_stability"], time_constant_factors=[1.0])
    assert not R.check_robust_stability(r["points"]["pid"], edges, "pid", req).passed


def test_routh_finding_says_no_end_of_the_box_is_a_routh_bound(model):
    finding = measure.routh_finding(model, _settings())
    check = C.check_routh_gives_paper_bounds(finding, _settings(), REQ["routh_gives_paper_bounds"])
    assert not check.passed and check.verdict == "warning"
    # Continuous PD: only kp > -1 (the DC loop gain), no upper bound.
    for entry in finding["continuous_kp"]:
        assert entry["intervals"][0][0] == pytest.approx(-1.0, abs=1e-6)
        assert entry["intervals"][-1][1] == finding["limit"]
    # The check can pass: a box whose ends are Routh's sampled bounds.
    kp_hi = finding["sampled_kp"][0]["intervals"][0][1]
    kd_lo, kd_hi = finding["sampled_kd"][0]["intervals"][0]
    box = _settings(kp_min=1.0, kp_max=kp_hi, kd_min=abs(kd_lo), kd_max=kd_hi)
    assert C.check_routh_gives_paper_bounds(finding, box, REQ["routh_gives_paper_bounds"]).passed


def test_overshoot_finding_reports_the_case1_numbers_and_flips_for_a_worse_pid():
    req = REQ["fgs_pd_overshoot_vs_pid"]
    case1 = measure.paper_case1(dict(DEFAULTS))
    check = C.check_fgs_pd_overshoot_vs_pid(case1, 1.18, req)
    assert not check.passed and check.verdict == "warning"
    assert "does not support the paper's claim" in check.measured
    # The numbers docs/control.md and the strict xfails of test_closed_loop.py quote.
    assert check.values["fgs_pd_paper_pct"] == pytest.approx([2.61, 4.44], abs=0.01)
    assert check.values["pid_pct"] == pytest.approx([2.19, 3.30], abs=0.01)
    assert check.values["fgs_pd_pure_pct"] == pytest.approx([1.63, 3.35], abs=0.01)
    # the default form (reference model, speed observer, no ramp integral) overshoots less
    # than the CPID
    assert check.values["fgs_pd_pct"] == pytest.approx([0.31, 1.05], abs=0.01)
    # A CPID with ten times the integral gain overshoots more: the claim then holds.
    worse = measure.paper_case1(dict(DEFAULTS, pid_ki=5.0))
    check = C.check_fgs_pd_overshoot_vs_pid(worse, 1.18, req)
    assert check.passed and check.values["pid_pct"][0] > check.values["fgs_pd_paper_pct"][0]


def test_exit_status_counts_failures_and_strict_counts_warnings():
    make = lambda passed, severity: C.Check("x", "t", "r", "m", passed, severity)  # noqa: E731
    checks = [make(True, "requirement"), make(False, "requirement"), make(False, "requirement"),
              make(False, "finding")]
    assert C.exit_status(checks) == 2
    assert C.exit_status(checks, strict=True) == 3


def _one_wheel_requirements(tmp_path):
    """The shipped requirements with the off-nominal grid cut to RobotPlant's own wheel at
    friction 0.05 (the whole grid takes half a minute)."""
    text = (Path(C.REQUIREMENTS_PATH).read_text()
            .replace("gain_factors = [0.25, 0.5, 1.0, 2.0, 4.0]\ntime_constant_factors = "
                     "[0.2, 0.5, 1.0, 2.0]", "gain_factors = [1.0]\ntime_constant_factors = [1.0]")
            .replace("frictions = [0.05, 0.1, 0.2, 0.4]", "frictions = [0.05]"))
    assert "gain_factors = [1.0]" in text and "frictions = [0.05]" in text
    path = tmp_path / "requirements.toml"
    path.write_text(text)
    return path


def test_cli_exit_status_is_the_number_of_failed_checks(tmp_path, capsys):
    from orchestrator.cli import main

    requirements = _one_wheel_requirements(tmp_path)
    arguments = ["verify", "--no-fmu", "--grid", "2", "--out", str(tmp_path),
                 "--requirements", str(requirements)]
    status = main(arguments)
    data = json.loads((tmp_path / "verification.json").read_text())
    failed = [c["name"] for c in data["checks"] if c["verdict"] == "FAIL"]
    warnings = {c["name"] for c in data["checks"] if c["verdict"] == "warning"}
    # every requirement holds (the findings about the paper are warnings)
    assert status == len(failed) == data["summary"]["exit_status"] == 0
    assert {"robust_stability_x4_fgs_pd", "robust_stability_x4_pd", "routh_gives_paper_bounds",
            "fgs_pd_overshoot_vs_pid", "load_step_recovery_paper",
            "load_step_recovery_pid"} <= warnings
    out = capsys.readouterr().out
    assert "warning robust_stability_x4_fgs_pd" in out
    assert "FGS-PD, default form: meets settling, load recovery, ramp lag, creep, limit " \
           "cycle, slip chatter (all six)." in out
    strict = main(arguments + ["--strict"])
    assert strict == len(failed) + len(warnings)
    # A requirement that fails counts once, and --strict adds the warnings.
    broken = load_requirements(requirements)
    broken["robust_stability"]["gain_factors"] = [0.25, 0.5, 1.0, 2.0, 4.0]
    report = verify(tmp_path / "broken", grid_size=2, fmu=False, plots=False,
                    requirements=broken)
    assert report.exit_status() == 2  # robust_stability_fgs_pd and _pd
    assert report.exit_status(strict=True) == 2 + len(warnings)
    assert json.loads((tmp_path / "verification.json").read_text())["summary"]["strict"]


def test_cli_names_a_missing_requirements_file_in_one_line(tmp_path, capsys):
    from orchestrator.cli import main

    status = main(["verify", "--no-fmu", "--out", str(tmp_path), "--requirements",
                   str(tmp_path / "missing.toml")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status != 0 and len(err) == 1 and "missing.toml" in err[0]


def test_unknown_requirement_severity_is_refused(tmp_path):
    path = tmp_path / "r.toml"
    path.write_text('[x]\ntitle = "t"\nwhy = "w"\nseverity = "maybe"\n')
    with pytest.raises(Exception, match="severity"):
        load_requirements(path)



@pytest.mark.parametrize("radius, says", [(1.093, "unstable: positive feedback"),
                                          (0.97, "stable even so")], ids=["above", "below"])
def test_the_literal_sign_reading_says_why_it_does_not_fail_the_box(radius, says):
    from orchestrator.verify.checks import _literal_signs

    text = _literal_signs(radius)
    assert f"max|z| = {radius:.3f}: {says}" in text

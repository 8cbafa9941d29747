"""The default wheel controller meets the off-nominal requirements through the built FMUs.

Two ways: the WheelController FMUs with RobotPlant (scaled to the wheel) in our master, as
`sonotrack verify` runs them; and the WheelController FMU driving first-order wheels this
test builds itself, with gains and time constants unlike RobotPlant's, integrated exactly
here. Each wheel is commissioned first (its two constants from a 1 V step, through the FMUs
or on the test's own wheel). In both the paper's form, told RobotPlant's constants, is the
broken controller that misses what the default meets.
"""

import math

import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from components.control.identification import fit_step_response
from orchestrator.verify.checks import load_requirements
from orchestrator.verify.commissioning import commission_fmu, commissioned
from orchestrator.verify.designs import design_settings
from orchestrator.verify.fmu_requirements import FmuLoop, _RUNS, fmu_requirements
from orchestrator.verify.wheel_experiments import plant_variant_parameters, settling_after

pytestmark = pytest.mark.integration

REQ = load_requirements()
DEFAULT = design_settings(dict(DEFAULTS), "default")
PAPER = design_settings(dict(DEFAULTS), "paper")


@pytest.fixture(scope="module")
def loop(fmu_paths):
    fmus = FmuLoop(fmu_paths["RobotPlant"], fmu_paths["WheelController"])
    yield fmus
    fmus.release()


def _run(loop, name, settings, cell, frictions=None, commission=True):
    grid = dict(REQ["off_nominal_grid"])
    if frictions is not None:
        grid["frictions"] = frictions
    if commission:
        fit = commission_fmu(loop, plant_variant_parameters(*cell), REQ["commissioning"])
        settings = commissioned(settings, fit)
    return _RUNS[name](loop, settings, PlantParameters(), cell, REQ[name], grid)


def test_commissioning_through_the_fmus_finds_the_wheels_constants(loop):
    # the scaled RobotPlant is the linear model's scaled wheel, but for its tyres' compliance,
    # which the fit sees as a longer time constant on the fastest wheel (+6.1 % at gain x4,
    # tau x0.2; under 1 % at x1): the volts per speed to 1 %, the time constant to 8 %
    from orchestrator.verify.loop_model import linear_wheel_model

    for cell in ((1.0, 1.0), (4.0, 0.2), (0.25, 2.0)):
        fit = commission_fmu(loop, plant_variant_parameters(*cell), REQ["commissioning"])
        model = linear_wheel_model(PlantParameters()).scaled(*cell)
        assert fit.volts_per_speed == pytest.approx(1.0 / model.dc_gain, rel=0.01), cell
        assert fit.time_constant == pytest.approx(model.time_constants[1], rel=0.08), cell


@pytest.mark.parametrize("cell", [(1.0, 1.0), (0.5, 1.0), (2.0, 2.0)],
                         ids=["nominal", "half-gain", "strong-heavy"])
@pytest.mark.parametrize("name", ["off_nominal_settling", "ramp_lag", "no_creep",
                                  "no_limit_cycle"])
def test_default_form_meets_the_requirements_with_robotplant_in_our_master(loop, name, cell):
    result = _run(loop, name, DEFAULT, cell)
    assert result["passed"], result


@pytest.mark.parametrize("cell", [(1.0, 1.0), (2.0, 2.0)], ids=["nominal", "strong-heavy"])
def test_load_step_runs_through_robotplant_as_its_load_torque_fault(loop, cell):
    result = _run(loop, "load_step_recovery", DEFAULT, cell)
    assert result["passed"], result
    # 20 % of the wheel's own stall torque at 11.1 V: eta N Kt G V / R at the wheel
    p = PlantParameters()
    stall = p.gear_efficiency * p.gear_ratio * p.torque_constant * cell[0] * p.v_supply \
        / p.motor_resistance
    assert result["load_torque_n_m"] == pytest.approx(0.2 * stall, rel=1e-9)
    # the load was felt: recovering takes time (0 would mean no load reached the wheel)
    assert result["value"] > 0.2
    assert not _run(loop, "load_step_recovery", PAPER, cell, commission=False)["passed"]


def test_default_form_does_not_chatter_at_friction_02_and_an_undamped_pd_does(loop):
    assert _run(loop, "no_slip_chatter", DEFAULT, (1.0, 1.0), frictions=[0.2])["value"] == 0
    undamped = dict(DEFAULT, mode="pd", pd_kp=14.0, pd_kd=0.0, speed_observer=0.0,
                    integral_gain=22.0, fuzzy_e_range=0.0259, fuzzy_de_range=0.432)
    assert not _run(loop, "no_slip_chatter", undamped, (1.0, 1.0), frictions=[0.2])["passed"]


def test_default_form_holds_the_tyre_at_friction_005_through_the_fmus(loop):
    # the judged failure of the default form before its speed observer (10 slides in 1 s)
    assert _run(loop, "no_slip_chatter", DEFAULT, (1.0, 1.0), frictions=[0.05])["passed"]
    before = dict(DEFAULT, speed_observer=0.0, integral_gain=22.0, fuzzy_e_range=0.0259,
                  fuzzy_de_range=0.432)
    assert not _run(loop, "no_slip_chatter", before, (1.0, 1.0), frictions=[0.05])["passed"]


def test_paper_form_misses_settling_at_half_the_gain_through_the_fmus(loop):
    result = _run(loop, "off_nominal_settling", PAPER, (0.5, 1.0), commission=False)
    assert not result["passed"] and result["value"] > 1.0


def test_fmu_results_agree_with_the_discrete_time_loop(fmu_dir):
    # settling on a wheel with half the gain: the FMUs (tyre compliance, 1e6 counts) and the
    # loop (rigid wheel, exact average) within two samples of each other
    from orchestrator.verify.requirement_runs import run_model_experiment

    fmu = fmu_requirements({"default": DEFAULT}, PlantParameters(), dict(
        REQ, off_nominal_grid=dict(REQ["off_nominal_grid"], frictions=[0.4])), [(0.5, 1.0)],
        fmu_dir=fmu_dir)["default"]
    from orchestrator.verify.commissioning import commission_model

    own = commissioned(DEFAULT, commission_model(PlantParameters(), (0.5, 1.0),
                                                 REQ["commissioning"]))
    model = run_model_experiment("off_nominal_settling", own, PlantParameters(), (0.5, 1.0),
                                 REQ, REQ["off_nominal_grid"])
    assert fmu["off_nominal_settling"][0]["value"] == pytest.approx(model["value"], abs=0.041)
    assert all(rows[0]["passed"] for rows in fmu.values())


class _FirstOrderWheel:
    """``tau dv/dt = gain V / g - v - load`` exact over a held 20 ms step; window average."""

    def __init__(self, gain, tau):
        self.gain, self.tau = gain, tau
        self.speed = self.measured = 0.0
        self.load = 0.0

    def step(self, voltage, h):
        target = self.gain * voltage / DEFAULTS["volts_per_speed"] - self.load
        decay = math.exp(-h / self.tau)
        travelled = target * h + (self.speed - target) * self.tau * (1.0 - decay)
        self.speed = target + (self.speed - target) * decay
        self.measured = travelled / h


def _commissioned_on(settings, gain, tau):
    """``settings`` with the constants a 1 V step for 1.5 s finds on this test's wheel."""
    wheel, h = _FirstOrderWheel(gain, tau), 0.02
    times, positions, position = [], [], 0.0
    for k in range(75):
        wheel.step(1.0, h)
        position += wheel.measured * h
        times.append((k + 1) * h)
        positions.append(position)
    return commissioned(settings, fit_step_response(times, positions, 1.0))


def _through_the_controller_fmu(path, settings, gain, tau, load_at=None):
    """The WheelController FMU on a first-order wheel: a 0.3 m/s step at 20 ms, a load of
    20 % of the wheel's stall speed drop at ``load_at``; the true speeds."""
    from orchestrator.fmu.handle import FmuInstance

    h, steps = 0.02, 400
    fmu = FmuInstance(path, f"first_order_{gain}_{tau}")
    fmu.instantiate(0.0, steps * h, parameters={
        k: v for k, v in settings.items() if k in fmu.variables})
    wheel = _FirstOrderWheel(gain, tau)
    times, speeds = [], []
    try:
        for k in range(steps):
            if load_at is not None and k * h >= load_at:
                # 20 % of the stall torque: 20 % of the no-load speed at 11.1 V
                wheel.load = 0.2 * gain * 11.1 / DEFAULTS["volts_per_speed"]
            fmu.set_values({"v_ref": 0.3 if k >= 1 else 0.0, "v_meas": wheel.measured})
            fmu.do_step(k * h, h)
            wheel.step(fmu.get_values(["voltage"])["voltage"], h)
            times.append((k + 1) * h)
            speeds.append(wheel.speed)
    finally:
        fmu.terminate()
    return times, speeds


@pytest.mark.parametrize("gain,tau", [(0.6, 0.25), (1.7, 0.6), (0.4, 0.15)],
                         ids=["weak-fast", "strong-slow", "weaker-faster"])
def test_controller_fmu_settles_first_order_wheels_within_1_s_exactly(fmu_paths, gain, tau):
    own = _commissioned_on(DEFAULT, gain, tau)
    assert own["volts_per_speed"] == pytest.approx(DEFAULTS["volts_per_speed"] / gain, rel=1e-6)
    assert own["acceleration_feedforward"] == pytest.approx(tau, rel=1e-6)
    times, speeds = _through_the_controller_fmu(fmu_paths["WheelController"], own, gain, tau)
    assert settling_after(times, speeds, 0.3, 0.006, 0.02) <= 1.0
    assert speeds[-1] == pytest.approx(0.3, abs=1e-6)   # steady state exact


def test_controller_fmu_recovers_from_a_load_step_on_a_first_order_wheel(fmu_paths):
    times, speeds = _through_the_controller_fmu(fmu_paths["WheelController"],
                                                _commissioned_on(DEFAULT, 0.6, 0.25), 0.6,
                                                0.25, load_at=4.0)
    assert settling_after(times, speeds, 0.3, 0.006, 4.0) <= 1.0
    assert min(s for t, s in zip(times, speeds) if t > 4.0) < 0.29   # the load was felt


def test_paper_form_fmu_misses_1_s_on_the_same_wheel(fmu_paths):
    # the finding: about 0.21 m/s after 4 s on a wheel unlike RobotPlant's
    times, speeds = _through_the_controller_fmu(fmu_paths["WheelController"], PAPER, 0.6, 0.25)
    assert settling_after(times, speeds, 0.3, 0.006, 0.02) > 1.0

"""The speed observer against an exact first-order wheel and an independent pole check."""

import math

import numpy as np
import pytest

from components.control import DEFAULTS, WheelSpeedController
from components.control.observer import SpeedObserver

H = 0.02
G = DEFAULTS["volts_per_speed"]
TAU = DEFAULTS["acceleration_feedforward"]
QUANTUM = 2.0 * math.pi * 0.06 / 728          # RobotPlant's encoder: one count [m]


class Wheel:
    """``tau dv/dt = gain V / g - v - load`` exact over a held step; the encoder's position
    (optionally in whole counts) and its window speed."""

    def __init__(self, gain=1.0, tau=TAU, load=0.0, counts=False):
        self.gain, self.tau, self.load, self.counts = gain, tau, load, counts
        self.speed = self.distance = 0.0
        self.reported = 0.0

    def step(self, voltage):
        target = self.gain * voltage / G - self.load
        decay = math.exp(-H / self.tau)
        self.distance += target * H + (self.speed - target) * self.tau * (1.0 - decay)
        self.speed = target + (self.speed - target) * decay
        position = (math.floor(self.distance / QUANTUM) * QUANTUM if self.counts
                    else self.distance)
        v_meas = (position - self.reported) / H
        self.reported = position
        return v_meas


def _drive(observer, wheel, voltages):
    estimates, truths, disturbances = [], [], []
    for voltage in voltages:
        v_meas = wheel.step(voltage)
        estimates.append(observer.update(v_meas, H, voltage))
        truths.append(wheel.speed)
        disturbances.append(observer.disturbance)
    return np.array(estimates), np.array(truths), np.array(disturbances)


@pytest.mark.parametrize("bandwidth", [5.0, 12.0, 40.0])
def test_error_poles_sit_at_the_chosen_rate(bandwidth):
    # independent of the class's own arithmetic: numpy's eigenvalues of (I - L C) A
    transition, _, gains = SpeedObserver(G, TAU, bandwidth).matrices(H)
    error = (np.eye(3) - np.outer(gains, [1.0, 0.0, 0.0])) @ np.array(transition)
    poles = np.linalg.eigvals(error)
    # a triple pole: numerically split by about eps^(1/3)
    assert np.allclose(poles, math.exp(-bandwidth * H), atol=1e-4)
    # broken gains (the prediction estimator's, read as a current estimator) miss it
    assert not np.allclose(np.linalg.eigvals(error @ error), math.exp(-bandwidth * H),
                           atol=1e-4)


def test_on_the_wheel_it_models_the_estimate_is_the_true_speed():
    rng = np.random.default_rng(3)
    voltages = rng.uniform(-6.0, 6.0, 200)
    estimates, truths, disturbances = _drive(SpeedObserver(G, TAU, 12.0), Wheel(), voltages)
    assert np.max(np.abs(estimates - truths)) < 1e-12
    assert np.max(np.abs(disturbances)) < 1e-12


def test_a_wheel_unlike_the_model_is_learnt_as_a_disturbance():
    # twice the gain, a load: the disturbance state takes the steady difference, the speed
    # estimate converges to the true speed (five time constants of the error poles: 0.4 s)
    wheel = Wheel(gain=2.0, tau=TAU, load=0.05)
    estimates, truths, disturbances = _drive(SpeedObserver(G, TAU, 12.0), wheel,
                                             np.full(150, 1.5))
    steady = 2.0 * 1.5 / G - 0.05 - 1.5 / G        # the drive the model misses [m/s]
    assert disturbances[-1] == pytest.approx(steady, rel=1e-6)
    assert estimates[-1] == pytest.approx(truths[-1], rel=1e-6)
    # early on it is wrong: the check above is not vacuous
    assert abs(estimates[5] - truths[5]) > 0.01


def test_between_counts_it_is_finer_than_the_encoder_speed():
    # a constant 0.3 m/s on a 728-count encoder: the window speed toggles by one count
    # (25.9 mm/s); the observer's estimate moves by a tenth of that once settled (2.6 mm/s
    # measured): at least five times finer
    wheel = Wheel(counts=True)
    observer = SpeedObserver(G, TAU, 12.0)
    voltage = 0.3 * G
    measured, estimates = [], []
    for _ in range(300):
        v_meas = wheel.step(voltage)
        measured.append(v_meas)
        estimates.append(observer.update(v_meas, H, voltage))
    quantum = QUANTUM / H
    assert np.ptp(measured[150:]) == pytest.approx(quantum, rel=1e-6)
    assert np.ptp(estimates[150:]) < 0.2 * quantum
    # that resolution is the default form's fuzzy universe edge (controller.DEFAULTS)
    assert np.ptp(estimates[150:]) == pytest.approx(DEFAULTS["fuzzy_e_range"], rel=0.02)
    assert DEFAULTS["fuzzy_de_range"] == pytest.approx(
        DEFAULTS["fuzzy_e_range"] / (DEFAULTS["derivative_time_constant"] + H), rel=1e-3)


def test_the_controller_refuses_an_observer_without_a_time_constant():
    with pytest.raises(Exception, match="speed_observer = 12.0 needs the wheel's time "
                                        "constant: acceleration_feedforward must be > 0"):
        WheelSpeedController(speed_observer=12.0, acceleration_feedforward=0.0)


def test_reset_puts_the_observer_at_rest():
    controller = WheelSpeedController()
    for _ in range(20):
        controller.step(0.3, 0.2, H)
    observer = controller.default_law.observer
    assert observer.speed != 0.0
    controller.reset()
    assert (observer.position, observer.speed, observer.disturbance,
            observer.measured_position) == (0.0, 0.0, 0.0, 0.0)

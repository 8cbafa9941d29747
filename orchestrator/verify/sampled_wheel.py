"""The discrete-time wheel loop, simulated: one linear wheel sampled exactly, the real controller.

:class:`SampledWheel` is the wheel of :mod:`.loop_model` (``LinearWheelModel``, scaled in DC
gain and time constant) advanced over one loop period ``T`` at a time with the voltage and a
load force held (zero-order hold, exact: one matrix exponential), and the speed its encoder
reports at the end of the period: the exact average of the rim speed over the window, or,
with ``counts_per_revolution``, the count difference over the window (the plant's
``WheelEncoder``: ``floor`` of the wheel angle in counts). :func:`run_loop` closes the loop
with :class:`components.control.WheelSpeedController` itself (saturation, anti-windup,
scheduling and every form's logic included), in the order of our Gauss-Seidel master: at
``t_k`` the controller reads the window that ended at ``t_k`` and its voltage is held over
``[t_k, t_k + T]``.

Without quantisation and with frozen gains this is exactly the closed-loop transfer function
of :meth:`.loop_model.WheelLoopModel.closed_loop_tf` (tested); unlike it, it has the voltage
limit, a load torque, the encoder's quantum and the controller's nonlinear parts.
"""

import math
from dataclasses import dataclass

import numpy as np

from components.common.errors import ConfigError

__all__ = ["SampledWheel", "LoopTrace", "run_loop", "stall_force"]


def stall_force(linear, v_supply):
    """Rim force of the wheel stalled at ``v_supply`` [N]: ``K_f G V / R``.

    The wheel's own stall force: a wheel with ``input_gain`` G receives G times the voltage.
    """
    return linear.input_gain * linear.force_per_current * v_supply / linear.resistance


class SampledWheel:
    """One wheel, sampled exactly at the loop period; voltage and load force held.

    Parameters
    ----------
    linear : LinearWheelModel
        The wheel (already scaled).
    period : float
        Loop period ``T`` [s] (the encoder window).
    counts_per_revolution : int, optional
        Encoder counts per wheel revolution; None: the measured speed is the exact window
        average (no quantisation).
    wheel_radius : float, optional
        [m]; converts rim distance to wheel angle for the encoder.
    v_supply : float, optional
        The driver's limit: the voltage is clipped to +-v_supply before the wheel's input
        gain acts [V].

    Attributes
    ----------
    current, rim_speed, distance : float
        State at the last sample: armature current [A], rim speed [m/s], rim distance [m].
    measured_speed : float
        The encoder's speed for the window that ended at the last sample [m/s].
    """

    def __init__(self, linear, period, counts_per_revolution=None, wheel_radius=0.06,
                 v_supply=11.1):
        from scipy.linalg import expm

        if not (math.isfinite(period) and period > 0.0):
            raise ConfigError(f"sampled wheel: period = {period!r} must be > 0")
        self.period = float(period)
        self.v_supply = float(v_supply)
        L, R, M = linear.inductance, linear.resistance, linear.effective_mass
        # State (i, u, q): current, rim speed, rim distance; inputs (V, F_load).
        block = np.zeros((5, 5))
        block[0, 0], block[0, 1] = -R / L, -linear.emf_per_speed / L
        block[1, 0], block[1, 1] = linear.force_per_current / M, -linear.damping / M
        block[2, 1] = 1.0
        block[0, 3] = linear.input_gain / L
        block[1, 4] = -1.0 / M
        exponential = expm(block * self.period)
        self._transition = exponential[:3, :3]
        self._input = exponential[:3, 3:]
        self.distance_per_count = (None if counts_per_revolution is None
                                   else 2.0 * math.pi * wheel_radius / counts_per_revolution)
        self.current = self.rim_speed = self.distance = 0.0
        self.measured_speed = 0.0
        self._count = 0

    def step(self, voltage, load_force=0.0):
        """Hold ``voltage`` [V] (clipped to the supply) and ``load_force`` [N] over one period.

        Returns
        -------
        float
            The measured speed of the window just ended [m/s].
        """
        voltage = min(max(voltage, -self.v_supply), self.v_supply)
        before = self.distance
        state = (self._transition @ np.array([self.current, self.rim_speed, self.distance])
                 + self._input @ np.array([voltage, load_force]))
        self.current, self.rim_speed, self.distance = (float(v) for v in state)
        if self.distance_per_count is None:
            self.measured_speed = (self.distance - before) / self.period
        else:
            count = math.floor(self.distance / self.distance_per_count)
            self.measured_speed = (count - self._count) * self.distance_per_count / self.period
            self._count = count
        return self.measured_speed


@dataclass
class LoopTrace:
    """Samples of one closed-loop run at ``t_k = k T`` (arrays of equal length).

    Attributes
    ----------
    t, reference, rim_speed, measured_speed, voltage, distance, load_force : numpy.ndarray
        ``voltage[k]`` is the voltage held over ``[t_k, t_k+1]`` (the last one is 0).
    kp, kd : numpy.ndarray
        The gains the controller used at ``t_k``.
    """

    t: np.ndarray
    reference: np.ndarray
    rim_speed: np.ndarray
    measured_speed: np.ndarray
    voltage: np.ndarray
    distance: np.ndarray
    load_force: np.ndarray
    kp: np.ndarray
    kd: np.ndarray


def run_loop(controller, wheel, reference, duration, load=None):
    """Close the loop of ``controller`` on ``wheel`` from rest for ``duration`` seconds.

    Parameters
    ----------
    controller : WheelSpeedController
    wheel : SampledWheel
    reference : callable
        ``reference(t)`` [m/s] at the sample times.
    duration : float
        [s]; ``round(duration / T)`` periods are run.
    load : callable, optional
        ``load(t)`` rim force [N] held over the period that starts at ``t``.

    Returns
    -------
    LoopTrace
    """
    T = wheel.period
    steps = int(round(duration / T))
    columns = np.zeros((9, steps + 1))
    for k in range(steps + 1):
        t = k * T
        r = reference(t)
        force = load(t) if load is not None else 0.0
        voltage = controller.step(r, wheel.measured_speed, T) if k < steps else 0.0
        columns[:, k] = (t, r, wheel.rim_speed, wheel.measured_speed, voltage, wheel.distance,
                         force, controller.kp, controller.kd)
        if k < steps:
            wheel.step(voltage, force)
    return LoopTrace(*columns)

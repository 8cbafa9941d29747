"""The default form of the FGS-PD and PD laws: model feedforward, speed observer, scaled PD,
stop reset.

Written out in physical units (``g = volts_per_speed``, ``e = v_ref - v_meas``, ``de`` its
filtered derivative)::

    V = clip( g v_ref + g tau_a dv_ref/dt                 [feedforward: motor model]
              - g d                                        [observed disturbance]
              + g s (kp e + kd T_d de)                     [the paper's PD, scaled by s]
              + g k_i integral(e dt),                      [integral of the speed error]
              +-limit )

- ``tau_a = acceleration_feedforward``: the voltage the wheel's inertia needs to follow a
  ramp (``M_eff dv/dt`` through the motor), so that the planner's ramps are followed without
  the lag ``a tau_m / (1 + kp)`` a PD leaves; ``dv_ref/dt`` is the reference's change over one
  step (0 on the first step).
- ``s = gain_scale``: kp and kd keep the paper's boxes and the fuzzy rules; ``s`` says what
  they multiply (``s kp`` is the DC loop gain on RobotPlant).
- ``T_d = derivative_time``: the derivative time per unit kd, kept short because the
  derivative of an encoder speed amplifies its quantum into the voltage (docs/control.md).
- ``k_i = integral_gain`` [1/s] on the integral of ``e``, the wheel's position lag [m]: zero
  steady-state error for any motor the loop is stable with. Anti-windup: conditional
  integration at the limit (the measured supply, as in :class:`.PidLaw`) and a clamp
  ``|g k_i I| <= v_supply``.
- While ``v_ref`` is exactly 0 and ``zero_reference_reset`` is on, the integral is emptied and
  held: a stopped robot has no steady voltage to hold, so nothing is left to make it creep.
- The fuzzy scheduler reads ``e / fuzzy_e_range`` and ``de / fuzzy_de_range``: the universe
  is sized to the errors the loop sees (docs/control.md); ``e_range`` and ``de_range`` are
  the paper form's (and the PID's) normalisation and are not read here.
- ``speed_observer`` [rad/s] (0: off): the error is taken against the rim speed a
  :class:`.observer.SpeedObserver` estimates between encoder counts (its model: ``g`` and
  ``tau_a``; its three error poles at that rate), compared with the reference model's speed
  rather than its window average; and the voltage ``g d`` of the disturbance it estimates
  (a load, friction, another motor constant) is taken away. The observer's disturbance state
  is then the loop's integral action (``integral_gain``, default 0, would add a second one);
  with ``zero_reference_reset`` it is not compensated while the reference is exactly 0 and
  starts from 0 on the first step after (the integral is emptied and held).
"""

import math

from .observer import SpeedObserver

__all__ = ["DefaultFormLaw"]


class DefaultFormLaw:
    """State and arithmetic of the default form (see the module docstring).

    Parameters
    ----------
    volts_per_speed : float
        ``g`` [V s/m].
    gain_scale : float
        ``s`` [1].
    derivative_time : float
        ``T_d`` [s]: the derivative time per unit kd.
    integral_gain : float
        ``k_i`` [1/s].
    acceleration_feedforward : float
        ``tau_a`` [s]; 0 switches the inertia term off.
    feedforward : bool
        Both model terms (``g v_ref`` and ``g tau_a dv_ref/dt``) on or off.
    zero_reference_reset : bool
        Empty and hold the integral while ``v_ref == 0``.
    v_supply : float
        The clamp of the integral term [V].
    speed_observer : float, optional
        The speed observer's rate [rad/s]; 0: the encoder's window speed is used as it is.

    Attributes
    ----------
    integral : float
        ``I``, the integral of ``e`` [m].
    previous_reference : float or None
        ``v_ref`` of the last step (None before the first).
    observer : SpeedObserver or None
    """

    def __init__(self, volts_per_speed, gain_scale, derivative_time, integral_gain,
                 acceleration_feedforward, feedforward, zero_reference_reset, v_supply,
                 speed_observer=0.0):
        self.g = float(volts_per_speed)
        self.proportional = self.g * float(gain_scale)
        self.derivative_time = float(derivative_time)
        self.integral_gain = float(integral_gain)
        self.acceleration_time = float(acceleration_feedforward) if feedforward else 0.0
        self.feedforward = bool(feedforward)
        self.zero_reference_reset = bool(zero_reference_reset)
        self.integral_volts_limit = float(v_supply)
        self.integral = 0.0
        self.previous_reference = None
        self.model_speed = self.model_measured = 0.0
        self._model_step = None
        self._model_decay = self._model_gain = self._model_average = 0.0
        self.observer = (SpeedObserver(self.g, acceleration_feedforward, speed_observer)
                         if speed_observer > 0.0 else None)

    def tracked_reference(self, v_ref):
        """The speed the measurement is compared with [m/s].

        With the inertia term on, the reference model's prediction of the measured speed
        (:attr:`model_measured`): the encoder speed a wheel with the nominal constants
        (``g``, ``tau_a``) would report under the feedforward alone. On such a wheel the
        feedback then sees no error at all, after a step as on a ramp, instead of acting a
        second time on what the feedforward already does; on any other wheel it sees
        exactly the difference. Without the inertia term, ``v_ref`` itself. With the speed
        observer, the model's speed at this instant (what the observer estimates), not its
        window average.
        """
        if self.acceleration_time:
            return self.model_measured if self.observer is None else self.model_speed
        return v_ref

    def measured_speed(self, v_meas, h, voltage):
        """The speed the error is taken against: ``v_meas``, or the observer's estimate.

        ``voltage`` is the one held over the period that just ended (the last output).
        """
        if self.observer is None:
            return v_meas
        return self.observer.update(v_meas, h, voltage)

    def output(self, v_ref, error, rate, kp, kd, h, limit):
        """One step: the clipped voltage [V]; advances the integral and the reference memory.

        Parameters
        ----------
        v_ref, error, rate : float
            Reference [m/s], the error against :meth:`tracked_reference` [m/s] and its
            filtered derivative [m/s^2].
        kp, kd : float
            The gains of this step.
        h : float
            Step [s], > 0.
        limit : float
            Output limit +-limit [V].
        """
        g = self.g
        offset = 0.0
        if self.feedforward:
            if self.acceleration_time:
                offset = g * self._model_drive(v_ref, h, limit / g)
            else:
                offset = g * v_ref
        stopped = self.zero_reference_reset and v_ref == 0.0
        if self.observer is not None and not stopped:
            if self.zero_reference_reset and self.previous_reference == 0.0:
                # the first step after a stop starts the observer's integral action afresh,
                # as the integral is emptied: what it learnt before the stop (a load, friction
                # in the direction the wheel turned) is not the next start's (a wheel that
                # spun backwards then drives forwards). Through the stop it keeps estimating,
                # so that the braking wheel's speed is estimated right.
                self.observer.disturbance = 0.0
            # the voltage the estimated disturbance takes away
            offset -= g * self.observer.disturbance
        self.previous_reference = v_ref
        pd = self.proportional * (kp * error + kd * self.derivative_time * rate)
        ki = self.integral_gain
        if stopped:
            self.integral = 0.0
        elif ki > 0.0:
            candidate = self.integral + error * h
            bound = self.integral_volts_limit / (g * ki)
            candidate = bound if candidate > bound else (-bound if candidate < -bound
                                                         else candidate)
            raw = offset + pd + g * ki * candidate
            # conditional integration: no integrating further into a saturated output
            if not ((raw > limit and error > 0.0) or (raw < -limit and error < 0.0)):
                self.integral = candidate
        raw = offset + pd + g * ki * self.integral
        return limit if raw > limit else (-limit if raw < -limit else raw)

    def _model_drive(self, v_ref, h, bound):
        """Feedforward speed [m/s] (``g`` times it is the voltage) and the model's advance.

        The drive that brings the nominal wheel ``tau_a du/dt = drive - u`` from the model's
        speed ``u_k`` to ``v_ref`` in one step, ``d = v_ref + a (v_ref - u_k) / (1 - a)``
        with ``a = exp(-h / tau_a)``, limited to +-``bound`` (the voltage limit); the model
        then moves with the drive it really got, and predicts the encoder's window average
        over the step, ``c u_k + (1 - c) d`` with ``c = tau_a (1 - a) / h``. On a ramp
        ``d = v_ref + a_ramp tau_a`` to first order: the voltage the inertia needs.
        """
        if h != self._model_step:
            decay = math.exp(-h / self.acceleration_time)
            self._model_step = h
            self._model_decay = decay
            self._model_gain = decay / (1.0 - decay)
            self._model_average = self.acceleration_time * (1.0 - decay) / h
        speed = self.model_speed
        drive = v_ref + self._model_gain * (v_ref - speed)
        drive = bound if drive > bound else (-bound if drive < -bound else drive)
        self.model_measured = drive + self._model_average * (speed - drive)
        self.model_speed = drive + self._model_decay * (speed - drive)
        return drive

    def reset(self):
        """Empty the integral, forget the reference and put the reference model at rest."""
        self.integral = 0.0
        self.previous_reference = None
        self.model_speed = self.model_measured = 0.0
        if self.observer is not None:
            self.observer.reset()

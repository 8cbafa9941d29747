"""The wheel-speed controller core: FGS-PD (the paper), PID (its CPID baseline) or fixed PD.

Two forms of the FGS-PD and fixed-PD laws (``form``): ``"default"``, the loop this repository
ships (:mod:`.default_form`: motor-model feedforward of speed and acceleration, the paper's
gain boxes on a stated scale, an integral of the speed error, reset while the reference is
held at zero; docs/control.md says why and what it measures), and ``"paper"``, the paper's
printed design as this repository first implemented it (below). The PID mode is the paper's
CPID in both forms. Each form reads its own parameters (:data:`FORM_PARAMETERS`); setting
one that the chosen form does not read is refused, never silently ignored.

Sign convention: the error is ``e = v_ref - v_meas`` (positive when the wheel is too slow)
and every gain is positive. The paper writes its error the other way round, so its negative
ranges Kp in [-4, -3], Kd in [-2, -0.3] are kp in [3, 4], kd in [0.3, 2] here, with "max"
the larger magnitude (see :data:`.fgs_pd.PAPER_TO_OURS`).

Control law, on normalised signals ``e_n = e / e_range`` and ``de_n = de / de_range`` (``de``
the filtered derivative of ``e``)::

    voltage = clip(g v_ref [feedforward] + g e_range (kp e_n + kd de_n [+ ki I]), +-v_supply)

where ``g = volts_per_speed`` is the motor's steady-state voltage per rim speed. The PD part is
thus a speed correction ``kp e + kd (e_range / de_range) de`` in m/s, turned into volts by the
same motor constant as the feedforward: ``kp`` is the dimensionless proportional loop gain at
DC, whatever the motor. The feedforward supplies the voltage the reference speed needs, so
the pure PD law has no steady-state error only when ``g`` matches the motor; a mismatch
``g_motor (1 + delta)`` leaves ``e_ss = -delta v_ref / (1 + (1 + delta) kp)``.

Output limit: ``+-v_supply``, or the measured supply of the motor driver when it is lower
(``supply``): a sagging battery saturates the driver below the nominal supply, and the
anti-windup of the integral terms can only stop integrating when it knows that limit.

The paper form. Integral trim (docs/control.md): the fgs_pd and pd modes add
``ki I`` with ``ki = trim_ki`` [1/s] and ``I`` the time integral of ``e_n`` (the PID's
integrator and anti-windup, :class:`.PidLaw`), so the steady-state error is zero for any
motor constant the loop is stable with. ``trim_ki = 0`` gives the pure PD of Eq. (46).
"""

import math

from ..common.errors import InputError, ParameterError
from .default_form import DefaultFormLaw
from .derivative import FilteredDerivative
from .fgs_pd import check_gain_range, scheduled_gain
from .inference import METHODS, FuzzyGainScheduler
from .pid import PidLaw

__all__ = ["WheelSpeedController", "MODES", "FORMS", "DEFAULTS", "FORM_PARAMETERS"]

MODES = ("fgs_pd", "pid", "pd")
FORMS = ("default", "paper")

# 14 * (Ke + R b / Kt) / r for the plant's defaults (docs/plant.md): 4.44 V per m/s.
_VOLTS_PER_SPEED = 14.0 * (0.01808 + 2.4 * 7.17e-6 / 0.01808) / 0.06
# M_eff R / (R B + K_f K_e) for the plant's defaults (docs/verification.md): the wheel's
# mechanical time constant, 0.390 s; g times it is the voltage per m/s^2 of acceleration.
_MECHANICAL_TIME_CONSTANT = 0.39

DEFAULTS = {
    "mode": "fgs_pd",
    "kp_min": 3.0, "kp_max": 4.0, "kd_min": 0.3, "kd_max": 2.0,
    "pid_kp": 3.0, "pid_ki": 0.5, "pid_kd": 1.0,
    "pd_kp": 3.5, "pd_kd": 1.15,
    "e_range": 0.4, "de_range": 4.0,
    "v_supply": 11.1,
    "derivative_time_constant": 0.04,
    "volts_per_speed": _VOLTS_PER_SPEED,
    "feedforward": True,
    "fuzzy_method": "weighted",
    "trim_ki": 0.5,
    "form": "default",
    "gain_scale": 1.2,
    # The speed observer's disturbance state is the integral action (0: no second one).
    "integral_gain": 0.0,
    "derivative_time": 0.01,
    # The smallest error the loop resolves is the edge of the default form's fuzzy universe:
    # with the speed observer, the peak-to-peak of its estimate at a constant 0.3 m/s on
    # RobotPlant's encoder, 2.6 mm/s (tests/unit/components/control/test_observer.py), and the
    # filtered derivative a step of that size gives, 2.6 mm/s / (tau + T) = 0.0433 m/s^2.
    # (Without the observer it was one encoder count per window: 25.9 mm/s, 0.432 m/s^2.)
    "fuzzy_e_range": 0.0026,
    "fuzzy_de_range": 0.0433,
    "acceleration_feedforward": _MECHANICAL_TIME_CONSTANT,
    "zero_reference_reset": True,
    # The speed observer's rate (docs/control.md: 12 rad/s meets every off-nominal requirement
    # on every wheel whose constants it is given; faster brings the encoder's toggles back).
    "speed_observer": 12.0,
}

# The parameters only one form reads; every other parameter means the same in both.
FORM_PARAMETERS = {
    "paper": ("trim_ki",),
    "default": ("gain_scale", "integral_gain", "derivative_time", "fuzzy_e_range",
                "fuzzy_de_range", "acceleration_feedforward", "zero_reference_reset",
                "speed_observer"),
}


class WheelSpeedController:
    """Speed controller of one wheel; see the module docstring for the law and conventions.

    Parameters
    ----------
    mode : {"fgs_pd", "pid", "pd"}
    kp_min, kp_max, kd_min, kd_max : float
        FGS-PD gain ranges of Eq. (50) [1], on e = v_ref - v_meas.
    pid_kp, pid_ki, pid_kd : float
        PID gains [1, 1/s, 1]; the paper's CPID: 3, 0.5, 1.
    pd_kp, pd_kd : float
        Fixed PD gains [1] (default: the middle of the FGS-PD ranges).
    e_range : float
        Error normalisation [m/s]: the error at the edge of the fuzzy universe.
    de_range : float
        Error-rate normalisation [m/s^2].
    v_supply : float
        Output limit +-v_supply [V].
    derivative_time_constant : float
        Time constant of the derivative's low-pass [s].
    volts_per_speed : float
        Steady-state armature voltage per rim speed [V s/m]; scales feedforward and PD output.
    feedforward : bool
        Add ``volts_per_speed * v_ref``.
    fuzzy_method : {"weighted", "mamdani"}
        Defuzzification of the FGS-PD fuzzy system (see :class:`.FuzzyGainScheduler`).
    trim_ki : float
        Paper form: integral trim of the fgs_pd and pd modes [1/s] on the time integral of
        ``e_n``; 0 switches it off (a pure PD, steady-state error unless the feedforward is
        exact).
    form : {"default", "paper"}
        The FGS-PD / PD design (module docstring); the PID is the CPID in both.
    gain_scale, integral_gain, derivative_time, fuzzy_e_range, fuzzy_de_range, \
acceleration_feedforward, zero_reference_reset, speed_observer
        Default form (:class:`.DefaultFormLaw`): factor on the PD [1], integral gain on
        ``e`` [1/s], derivative time per unit kd [s], the fuzzy universe's edges [m/s,
        m/s^2], the inertia feedforward's time [s] (0: off), whether the integral is
        emptied while ``v_ref`` is 0, and the speed observer's rate [rad/s] (0: off; it
        needs ``acceleration_feedforward`` > 0 as its model's time constant).

    Raises
    ------
    ParameterError
        Naming every invalid parameter, including a parameter set to other than its
        default that the chosen form does not read (:data:`FORM_PARAMETERS`).

    Attributes
    ----------
    error, error_rate, kp, kd, voltage : float
        Values of the last step (for plots); ``kp``/``kd`` are the gains used.
    """

    def __init__(self, **parameters):
        unknown = sorted(set(parameters) - set(DEFAULTS))
        if unknown:
            raise ParameterError(f"WheelController: unknown parameters {unknown}; valid: "
                                 f"{sorted(DEFAULTS)}")
        p = dict(DEFAULTS, **parameters)
        problems = []
        if p["mode"] not in MODES:
            problems.append(f"mode = {p['mode']!r} is not one of {', '.join(MODES)}")
        if p["fuzzy_method"] not in METHODS:
            problems.append(f"fuzzy_method = {p['fuzzy_method']!r} is not one of "
                            f"{', '.join(METHODS)}")
        if p["form"] not in FORMS:
            problems.append(f"form = {p['form']!r} is not one of {', '.join(FORMS)}")
        else:
            problems += _unread_by_form(p)
        for name in ("e_range", "de_range", "v_supply", "volts_per_speed", "gain_scale",
                     "fuzzy_e_range", "fuzzy_de_range"):
            if not (math.isfinite(p[name]) and p[name] > 0.0):
                problems.append(f"{name} = {p[name]!r} must be a positive finite number")
        for name in ("pid_kp", "pid_ki", "pid_kd", "pd_kp", "pd_kd", "derivative_time_constant",
                     "trim_ki", "integral_gain", "derivative_time", "acceleration_feedforward",
                     "speed_observer"):
            if not (math.isfinite(p[name]) and p[name] >= 0.0):
                problems.append(f"{name} = {p[name]!r} must be finite and >= 0")
        for name in ("kp", "kd"):
            try:
                check_gain_range(name, p[name + "_min"], p[name + "_max"])
            except ParameterError as exc:
                problems.append(str(exc))
        if p["speed_observer"] > 0.0 and not p["acceleration_feedforward"] > 0.0:
            problems.append(f"speed_observer = {p['speed_observer']!r} needs the wheel's time "
                            "constant: acceleration_feedforward must be > 0 (it is "
                            f"{p['acceleration_feedforward']!r})")
        if problems:
            raise ParameterError("WheelController parameters: " + "; ".join(problems))

        self.mode = p["mode"]
        self.kp_min, self.kp_max = float(p["kp_min"]), float(p["kp_max"])
        self.kd_min, self.kd_max = float(p["kd_min"]), float(p["kd_max"])
        self.pd_kp, self.pd_kd = float(p["pd_kp"]), float(p["pd_kd"])
        self.e_range, self.de_range = float(p["e_range"]), float(p["de_range"])
        self.v_supply = float(p["v_supply"])
        self.volts_per_speed = float(p["volts_per_speed"])
        self.feedforward = bool(p["feedforward"])
        self.to_voltage = self.volts_per_speed * self.e_range
        self.form = p["form"]
        # The PID is the CPID in both forms; the default form changes the FGS-PD and PD.
        self.default_law = None
        if self.form == "default" and self.mode != "pid":
            self.scheduler = FuzzyGainScheduler(float(p["fuzzy_e_range"]),
                                                float(p["fuzzy_de_range"]),
                                                method=p["fuzzy_method"])
            self.default_law = DefaultFormLaw(
                self.volts_per_speed, p["gain_scale"], p["derivative_time"],
                p["integral_gain"], p["acceleration_feedforward"], self.feedforward,
                p["zero_reference_reset"], self.v_supply, p["speed_observer"])
        else:
            self.scheduler = FuzzyGainScheduler(self.e_range, self.de_range,
                                                method=p["fuzzy_method"])
        self.derivative = FilteredDerivative(float(p["derivative_time_constant"]))
        self.pid = PidLaw(p["pid_kp"], p["pid_ki"], p["pid_kd"],
                          integral_limit=self.v_supply / self.to_voltage)
        self.trim_ki = float(p["trim_ki"])
        # The trim is the PID's integrator with the PD gains of the step (set before use).
        self.trim = PidLaw(0.0, self.trim_ki, 0.0,
                           integral_limit=self.v_supply / self.to_voltage)
        self.error = 0.0
        self.error_rate = 0.0
        self.kp, self.kd = self._initial_gains()
        self.voltage = 0.0

    def _initial_gains(self):
        if self.mode == "fgs_pd":
            kp_n, kd_n = self.scheduler.evaluate_normalised(0.0, 0.0)
            return (scheduled_gain(kp_n, self.kp_min, self.kp_max),
                    scheduled_gain(kd_n, self.kd_min, self.kd_max))
        if self.mode == "pid":
            return self.pid.kp, self.pid.kd
        return self.pd_kp, self.pd_kd

    def step(self, v_ref, v_meas, h, supply=None):
        """Compute the armature voltage for one control period.

        Parameters
        ----------
        v_ref : float
            Reference rim speed [m/s].
        v_meas : float
            Measured rim speed [m/s] (from the encoder).
        h : float
            Control period [s], > 0.
        supply : float, optional
            Measured supply voltage of the motor driver [V], >= 0. The output is limited to
            ``+-min(v_supply, supply)`` and the integral terms' anti-windup acts at that
            limit. None: ``v_supply``.

        Returns
        -------
        float
            Voltage [V] in [-limit, limit].

        Raises
        ------
        InputError
            If ``v_ref`` or ``v_meas`` is not finite, ``h`` is not positive or ``supply`` is
            negative or not finite; state unchanged.
        """
        if not math.isfinite(v_ref):
            raise InputError(f"WheelController input v_ref = {v_ref!r} is not finite")
        if not math.isfinite(v_meas):
            raise InputError(f"WheelController input v_meas = {v_meas!r} is not finite")
        if not (math.isfinite(h) and h > 0.0):
            raise InputError(f"WheelController step size = {h!r} must be > 0")
        limit = self.v_supply
        if supply is not None:
            if not (math.isfinite(supply) and supply >= 0.0):
                raise InputError(f"WheelController input supply_voltage = {supply!r} must be "
                                 "a finite voltage >= 0")
            if supply < limit:
                limit = supply
        law = self.default_law
        if law is not None:
            v_meas = law.measured_speed(v_meas, h, self.voltage)
        error = (v_ref if law is None else law.tracked_reference(v_ref)) - v_meas
        rate = self.derivative.update(error, h)
        if law is not None:
            if self.mode == "fgs_pd":
                scheduler = self.scheduler
                kp_n, kd_n = scheduler.evaluate_normalised(error / scheduler.e_range,
                                                           rate / scheduler.de_range)
                self.kp = (self.kp_max - self.kp_min) * kp_n + self.kp_min
                self.kd = (self.kd_max - self.kd_min) * kd_n + self.kd_min
            voltage = law.output(v_ref, error, rate, self.kp, self.kd, h, limit)
            self.error = error
            self.error_rate = rate
            self.voltage = voltage
            return voltage
        e_n = error / self.e_range
        de_n = rate / self.de_range
        offset = self.volts_per_speed * v_ref if self.feedforward else 0.0
        if self.mode == "pid":
            voltage = self.pid.output(e_n, de_n, h, self.to_voltage, offset, limit)
        else:
            if self.mode == "fgs_pd":
                kp_n, kd_n = self.scheduler.evaluate_normalised(e_n, de_n)
                self.kp = (self.kp_max - self.kp_min) * kp_n + self.kp_min
                self.kd = (self.kd_max - self.kd_min) * kd_n + self.kd_min
            if self.trim_ki > 0.0:
                trim = self.trim
                trim.kp, trim.kd = self.kp, self.kd
                voltage = trim.output(e_n, de_n, h, self.to_voltage, offset, limit)
            else:
                raw = offset + self.to_voltage * (self.kp * e_n + self.kd * de_n)
                voltage = limit if raw > limit else (-limit if raw < -limit else raw)
        self.error = error
        self.error_rate = rate
        self.voltage = voltage
        return voltage

    def reset(self):
        """Return to the state after construction (integrator and filter emptied)."""
        self.derivative.reset()
        self.pid.reset()
        self.trim.reset()
        if self.default_law is not None:
            self.default_law.reset()
        self.error = 0.0
        self.error_rate = 0.0
        self.kp, self.kd = self._initial_gains()
        self.voltage = 0.0


def _unread_by_form(parameters):
    """Problems: parameters set to other than their default that ``form`` does not read."""
    form = parameters["form"]
    return [f"{name} = {parameters[name]!r} is read only by form = {other!r}, not by form = "
            f"{form!r} (leave it at {DEFAULTS[name]!r} or choose form = {other!r})"
            for other, names in FORM_PARAMETERS.items() if other != form
            for name in names if parameters[name] != DEFAULTS[name]]

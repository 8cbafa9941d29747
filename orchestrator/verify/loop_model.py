"""The sampled wheel-speed loop: linearised plant, ZOH, window-averaged encoder, controller.

Model (derived in ``docs/verification.md``): one wheel driving straight without slip, the
voltage-to-rim-speed transfer function of ``docs/plant.md``, held by a zero-order hold over
the speed loop's period ``T`` (20 ms); the measured speed is the exact average of the rim
speed over the last encoder window (what a count difference over ``speed_window`` is, minus
the quantisation); the controller is :class:`components.control.WheelSpeedController`
written as a transfer function at the same period (filtered derivative by backward Euler,
integral accumulated before use). We analyse in discrete time because a continuous PD on the
second-order motor has no finite Routh-Hurwitz gain bound (checked and reported): the
finite bounds come from the sampling and the measurement's delay, so only a sampled model can
say how far the paper's gains are from them.

For robustness the plant can be scaled away from RobotPlant's defaults
(``gain_factor``: rim speed per volt; ``time_constant_factor``: the effective mass, hence
the mechanical time constant) while the controller keeps the constants tuned for RobotPlant.
"""

import math
from dataclasses import dataclass, field, replace

import numpy as np

from components.common.errors import ConfigError
from components.control.controller import DEFAULTS as CONTROLLER_DEFAULTS
from components.plant.parameters import PlantParameters

__all__ = ["LinearWheelModel", "WheelLoopModel", "linear_wheel_model", "zoh_with_average"]

# ----- the plant, linearised ------------------------------------------------------------------
@dataclass(frozen=True)
class LinearWheelModel:
    """Per-wheel linear model of docs/plant.md (straight line, no slip), SI units.

    ``u(s)/V(s) = K_f / ((L s + R)(M_eff s + B) + K_f K_e)``, u the rim speed.

    Attributes
    ----------
    inductance, resistance : float
        Armature L [H], R [Ohm].
    effective_mass : float
        ``m/2 + J_eff / r^2`` [kg], ``J_eff = J_wheel + eta N^2 J_rotor``.
    force_per_current : float
        ``K_f = eta N Kt / r`` [N/A].
    emf_per_speed : float
        ``K_e = N Ke / r`` [V s/m].
    damping : float
        ``B = eta N^2 b / r^2`` [N s/m].
    input_gain : float
        Factor on the armature voltage the motor actually receives (1 for RobotPlant; a
        sagging battery, a weaker driver or a different motor constant change it). It
        scales the DC gain and nothing else.
    """

    inductance: float
    resistance: float
    effective_mass: float
    force_per_current: float
    emf_per_speed: float
    damping: float
    input_gain: float = 1.0

    def scaled(self, gain_factor=1.0, time_constant_factor=1.0):
        """This wheel with its DC gain and mechanical time constant multiplied.

        ``gain_factor`` multiplies :attr:`input_gain`; ``time_constant_factor`` multiplies
        the effective mass, which (the electrical pole being 400 times faster) scales the
        mechanical time constant by the same factor to within 0.3 %.

        Returns
        -------
        LinearWheelModel
        """
        for name, value in (("gain_factor", gain_factor),
                            ("time_constant_factor", time_constant_factor)):
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"scaled wheel model: {name} = {value!r} must be > 0")
        return replace(self, input_gain=self.input_gain * gain_factor,
                       effective_mass=self.effective_mass * time_constant_factor)

    @property
    def numerator(self):
        """Numerator of u/V in s, highest power first."""
        return np.array([self.input_gain * self.force_per_current])

    @property
    def denominator(self):
        """Denominator of u/V in s, highest power first."""
        product = np.polymul([self.inductance, self.resistance],
                             [self.effective_mass, self.damping])
        product[-1] += self.force_per_current * self.emf_per_speed
        return product

    @property
    def dc_gain(self):
        """Steady rim speed per volt [m/s per V]."""
        return self.numerator[-1] / self.denominator[-1]

    @property
    def time_constants(self):
        """(electrical, mechanical) time constants [s] from the two real poles."""
        poles = np.sort(np.roots(self.denominator).real)
        return float(-1.0 / poles[0]), float(-1.0 / poles[1])

    def state_space(self):
        """``(A, B, C)`` with state (current, rim speed), input V, output rim speed."""
        L, R, M = self.inductance, self.resistance, self.effective_mass
        a = np.array([[-R / L, -self.emf_per_speed / L],
                      [self.force_per_current / M, -self.damping / M]])
        b = np.array([[self.input_gain / L], [0.0]])
        c = np.array([[0.0, 1.0]])
        return a, b, c

    def transfer_function(self):
        """The continuous u/V as a :class:`control.TransferFunction`."""
        import control

        return control.tf(self.numerator, self.denominator)


def linear_wheel_model(parameters=None):
    """Linearise one wheel of the RobotPlant core for straight driving without slip.

    Parameters
    ----------
    parameters : PlantParameters, optional
        Defaults to ``PlantParameters()``.

    Returns
    -------
    LinearWheelModel

    Notes
    -----
    With no slip the rim speed is the contact point's ground speed and, driving straight,
    each wheel carries half the body: the wheel equation
    ``J_eff dw/dt = eta N (Kt i - b N w) - r F`` with ``F = (m/2) du/dt`` and ``u = r w``
    gives ``M_eff du/dt = K_f i - B u``. Tyre compliance (slip stiffness) and the friction
    circle are left out; both are far faster, or inactive, in a straight speed step.
    """
    p = (parameters or PlantParameters()).validate()
    N, r, eta = p.gear_ratio, p.wheel_radius, p.gear_efficiency
    inertia = p.wheel_inertia + eta * N * N * p.rotor_inertia
    return LinearWheelModel(
        inductance=p.motor_inductance,
        resistance=p.motor_resistance,
        effective_mass=0.5 * p.mass + inertia / r ** 2,
        force_per_current=eta * N * p.torque_constant / r,
        emf_per_speed=N * p.back_emf_constant / r,
        damping=eta * N * N * p.motor_viscous_friction / r ** 2,
    )


# ----- the sampled loop -----------------------------------------------------------------------
def zoh_with_average(a, b, c, period):
    """ZOH discretisation and the exact window average of the output (Van Loan's method).

    Augment the state with the output's integral; one matrix exponential of
    ``[[A, 0, B], [C, 0, 0], [0, 0, 0]] T`` gives ``Ad, Bd`` and the integral's increment
    over one period, ``q_k+1 - q_k = Cq x_k + Dq V_k``. Dividing by ``T`` is the average.
    """
    from scipy.linalg import expm

    n = a.shape[0]
    block = np.zeros((n + 2, n + 2))
    block[:n, :n] = a
    block[n, :n] = c[0]
    block[:n, n + 1] = b[:, 0]
    exponential = expm(block * period)
    ad = exponential[:n, :n]
    bd = exponential[:n, n + 1:n + 2]
    average_c = exponential[n:n + 1, :n] / period
    average_d = exponential[n, n + 1] / period
    return ad, bd, average_c, average_d


def _ss_to_poly(a, b, c, d):
    """Numerator and denominator (highest power first) of a SISO state-space system."""
    from scipy.signal import ss2tf

    numerator, denominator = ss2tf(a, b, c, np.atleast_2d(d))
    numerator = np.trim_zeros(numerator[0], "f")
    return (numerator if numerator.size else np.array([0.0])), denominator


@dataclass
class WheelLoopModel:
    """The sampled wheel-speed loop: ZOH plant, window-averaged measurement, the controller.

    Parameters
    ----------
    plant : PlantParameters
        The plant; the period defaults to its ``speed_window``.
    period : float, optional
        Speed-loop sampling period [s]; None means ``plant.speed_window`` (20 ms).
    e_range, de_range, derivative_time_constant, volts_per_speed : float, optional
        Controller parameters (defaults: :data:`components.control.DEFAULTS`).
    feedforward : bool, optional
        The controller's ``g v_ref`` term.
    acceleration_feedforward : float, optional
        The default form's reference model, time constant ``tau_a`` [s] (0: none; only
        with ``feedforward``): the feedforward drives a nominal first-order wheel to the
        reference in one period, ``F = g (1 + A (1 - z^-1))`` with ``A = a / (1 - a)``,
        ``a = exp(-T / tau_a)``, and the feedback compares the measurement with that
        wheel's window average, ``M(z) r`` (:meth:`reference_model`).
    extra_delay : int, optional
        Additional whole samples between measurement and voltage: 0 for our Gauss-Seidel
        master (the controller reads the sample the plant finished at ``t_k`` and its voltage
        is held over ``[t_k, t_k + T]``), 1 for a Jacobi master.
    gain_factor, time_constant_factor : float, optional
        The wheel the controller drives, relative to RobotPlant's (see
        :meth:`LinearWheelModel.scaled`); the controller's constants stay as given.
    speed_observer, observer_time_constant : float, optional
        The default form's speed observer (:class:`components.control.observer.SpeedObserver`):
        its poles' rate [rad/s] (0: none) and its model's time constant [s]. The law then
        compares the observer's speed with the reference model's speed (``r / z``) and takes
        away ``g`` times the observed disturbance (:meth:`observer_polys`).
    """

    plant: PlantParameters = field(default_factory=PlantParameters)
    period: float = None
    e_range: float = CONTROLLER_DEFAULTS["e_range"]
    de_range: float = CONTROLLER_DEFAULTS["de_range"]
    derivative_time_constant: float = CONTROLLER_DEFAULTS["derivative_time_constant"]
    volts_per_speed: float = CONTROLLER_DEFAULTS["volts_per_speed"]
    feedforward: bool = CONTROLLER_DEFAULTS["feedforward"]
    acceleration_feedforward: float = 0.0
    extra_delay: int = 0
    gain_factor: float = 1.0
    time_constant_factor: float = 1.0
    speed_observer: float = 0.0
    observer_time_constant: float = 0.0

    def __post_init__(self):
        if self.period is None:
            self.period = self.plant.speed_window
        problems = []
        for name in ("period", "e_range", "de_range", "volts_per_speed"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                problems.append(f"{name} = {value!r} must be a positive finite number")
        if not (math.isfinite(self.derivative_time_constant)
                and self.derivative_time_constant >= 0):
            problems.append(f"derivative_time_constant = {self.derivative_time_constant!r} "
                            "must be finite and >= 0")
        if not (math.isfinite(self.acceleration_feedforward)
                and self.acceleration_feedforward >= 0):
            problems.append(f"acceleration_feedforward = {self.acceleration_feedforward!r} "
                            "must be finite and >= 0")
        if not (math.isfinite(self.speed_observer) and self.speed_observer >= 0):
            problems.append(f"speed_observer = {self.speed_observer!r} must be finite and >= 0")
        elif self.speed_observer > 0 and not self.observer_time_constant > 0:
            problems.append(f"observer_time_constant = {self.observer_time_constant!r} must be "
                            "> 0 with a speed observer")
        if int(self.extra_delay) != self.extra_delay or self.extra_delay < 0:
            problems.append(f"extra_delay = {self.extra_delay!r} must be an integer >= 0")
        if problems:
            raise ConfigError("verification loop model: " + "; ".join(problems))
        self.linear = linear_wheel_model(self.plant).scaled(self.gain_factor,
                                                            self.time_constant_factor)
        a, b, c = self.linear.state_space()
        ad, bd, average_c, average_d = zoh_with_average(a, b, c, self.period)
        self.discrete = (ad, bd, c)
        # Voltage -> rim speed at the sampling instants.
        self.rim_num, self.rim_den = _ss_to_poly(ad, bd, c, 0.0)
        # Voltage -> measured speed: the average over [t_k-1, t_k] depends on x_k-1 and V_k-1,
        # so the window average is one sample late (z^-1), plus any extra master delay.
        num, den = _ss_to_poly(ad, bd, average_c, average_d)
        self.meas_num = num
        self.meas_den = np.polymul(den, np.r_[1.0, np.zeros(1 + int(self.extra_delay))])

    # -- controller ----------------------------------------------------------------------
    def controller_poly(self, kp, kd, ki=0.0):
        """Numerator and denominator in z of the error -> voltage law (volts per m/s).

        ``g (kp + kd (e_range/de_range) (z - 1) / ((tau + T) z - tau) + ki T z / (z - 1))``:
        the backward-Euler filtered derivative of :class:`FilteredDerivative` and the
        integral of :class:`PidLaw` (``I_k = I_k-1 + T e_k``, used in the same step).
        """
        T, tau, g = self.period, self.derivative_time_constant, self.volts_per_speed
        derivative_den = np.array([tau + T, -tau])
        rate_gain = kd * self.e_range / self.de_range
        numerator = np.polyadd(kp * derivative_den, rate_gain * np.array([1.0, -1.0]))
        denominator = derivative_den
        if ki:
            numerator = np.polyadd(np.polymul(numerator, [1.0, -1.0]),
                                   ki * T * np.polymul([1.0, 0.0], derivative_den))
            denominator = np.polymul(denominator, [1.0, -1.0])
        return g * numerator, denominator

    # -- polynomials ---------------------------------------------------------------------
    def observer_polys(self):
        """The speed observer as polynomials in z: ``(Do, Nuv, Ndv, Nuy, Ndy)``.

        The observer's speed and disturbance estimates are ``u = (Nuv V + Nuy Vm) / Do`` and
        ``d = (Ndv V + Ndy Vm) / Do`` (``V`` the voltage, ``Vm`` the measured speed). It is
        the current estimator of :class:`components.control.observer.SpeedObserver`:
        ``x_k = (I - L C)(A x_k-1 + B V_k-1 / g) + L p_k`` on the position
        ``p = T z / (z - 1) Vm`` the measured speeds add up to; its response to ``p`` has a
        zero at ``z = 1`` (a constant position is a wheel at rest), which cancels that
        integrator (checked).
        """
        from components.control.observer import SpeedObserver

        observer = SpeedObserver(self.volts_per_speed, self.observer_time_constant,
                                 self.speed_observer)
        transition, drive, gains = (np.array(m, dtype=float)
                                    for m in observer.matrices(self.period))
        correct = np.eye(3) - np.outer(gains, [1.0, 0.0, 0.0])
        closed = correct @ transition
        per_volt = (correct @ drive / self.volts_per_speed)[:, None]
        polys = []
        for row in (1, 2):
            pick = np.eye(3)[row:row + 1]
            num_v, den = _ss_to_poly(closed, per_volt, pick, 0.0)
            num_p, _ = _ss_to_poly(closed, gains[:, None], pick, 0.0)
            # p = T z / (z - 1) Vm, and the estimator reads p_k through z L: T z^2 / (z - 1)
            quotient, remainder = np.polydiv(num_p, [1.0, -1.0])
            if np.max(np.abs(remainder)) > 1e-9 * max(1.0, np.max(np.abs(num_p))):
                raise ConfigError("speed observer: its response to position has no zero at "
                                  f"z = 1 (remainder {remainder})")
            polys.append((num_v, self.period * np.polymul(quotient, [1.0, 0.0, 0.0])))
        (nuv, nuy), (ndv, ndy) = polys
        return den, nuv, ndv, nuy, ndy

    def _observed_loop(self, kp, kd, ki):
        """``(A, B)``: the law with the observer is ``V A = (F + C M) r Dc Do - B Vm`` over
        ``Dc Do``: ``A = Dc Do + Nc Nuv + g Dc Ndv``, ``B = Nc Nuy + g Dc Ndy``."""
        nc, dc = self.controller_poly(kp, kd, ki)
        do, nuv, ndv, nuy, ndy = self.observer_polys()
        g = self.volts_per_speed
        own = np.polyadd(np.polyadd(np.polymul(dc, do), np.polymul(nc, nuv)),
                         g * np.polymul(dc, ndv))
        measured = np.polyadd(np.polymul(nc, nuy), g * np.polymul(dc, ndy))
        return own, measured

    def characteristic_polynomial(self, kp, kd, ki=0.0):
        """``Dc Dm + Nc Nm``: the closed-loop characteristic polynomial in z.

        With the speed observer, ``A Dm + B Nm`` (:meth:`_observed_loop`).
        """
        if self.speed_observer:
            own, measured = self._observed_loop(kp, kd, ki)
            return np.polyadd(np.polymul(own, self.meas_den), np.polymul(measured, self.meas_num))
        nc, dc = self.controller_poly(kp, kd, ki)
        return np.polyadd(np.polymul(dc, self.meas_den), np.polymul(nc, self.meas_num))

    def characteristic_in_kp(self, kd, ki=0.0):
        """``(base, per_kp)`` with characteristic polynomial ``base + kp * per_kp``."""
        base = self.characteristic_polynomial(0.0, kd, ki)
        per_kp = np.polysub(self.characteristic_polynomial(1.0, kd, ki), base)
        return base, per_kp

    def characteristic_in_gain_factor(self, kp, kd, ki=0.0):
        """``(base, per_gain)`` with characteristic polynomial ``base + G * per_gain``.

        ``G`` is the plant's DC-gain factor relative to RobotPlant's (absolute, not relative
        to this model's :attr:`gain_factor`). The factor multiplies the voltage the motor
        receives, so it scales the plant's numerator and nothing else: ``Dc Dm + G Nc Nm1``
        with ``Nm1`` the measured-speed numerator at ``G = 1``.
        """
        if self.speed_observer:
            dc, nc = self._observed_loop(kp, kd, ki)
        else:
            nc, dc = self.controller_poly(kp, kd, ki)
        base = np.polymul(dc, self.meas_den)
        per_gain = np.polymul(nc, self.meas_num) / self.gain_factor
        length = max(base.size, per_gain.size)
        return (np.pad(base, (length - base.size, 0)),
                np.pad(per_gain, (length - per_gain.size, 0)))

    def characteristic_in_kd(self, kp, ki=0.0):
        """``(base, per_kd)`` with characteristic polynomial ``base + kd * per_kd``."""
        base = self.characteristic_polynomial(kp, 0.0, ki)
        per_kd = np.polysub(self.characteristic_polynomial(kp, 1.0, ki), base)
        return base, per_kd

    # -- python-control views ---------------------------------------------------------------
    def _tf(self, num, den):
        import control

        return control.tf(num, den, self.period)

    def loop_tf(self, kp, kd, ki=0.0):
        """Open loop ``C(z) H(z)`` (voltage law times measured-speed path), for margins.

        With the speed observer, broken at the plant's input (the observer still reads the
        law's own voltage): ``B H / A`` (:meth:`_observed_loop`).
        """
        if self.speed_observer:
            own, measured = self._observed_loop(kp, kd, ki)
            return self._tf(np.polymul(measured, self.meas_num), np.polymul(own, self.meas_den))
        nc, dc = self.controller_poly(kp, kd, ki)
        return self._tf(np.polymul(nc, self.meas_num), np.polymul(dc, self.meas_den))

    def closed_loop_tf(self, kp, kd, ki=0.0, output="rim"):
        """Reference -> rim speed (``output="rim"``) or -> measured speed (``"measured"``).

        ``G (F + C) / (1 + C H)`` with ``F = g`` the feedforward (0 if switched off); with
        the reference model, ``G (F + C M) / (1 + C H)`` (:meth:`reference_model`).
        """
        nc, dc = self.controller_poly(kp, kd, ki)
        forward = self.volts_per_speed if self.feedforward else 0.0
        # F + C = (F Dc + Nc) / Dc; 1 + C H = (Dc Dm + Nc Nm) / (Dc Dm).
        drive = np.polyadd(forward * dc, nc)
        characteristic = self.characteristic_polynomial(kp, kd, ki)
        if self.speed_observer:
            # V A = (F + C M) Dc Do r - B Vm with M = 1 / z (the reference model's speed)
            # when the inertia term is on, else 1: V = (F + C M) Dc Do Dm / char r.
            do = self.observer_polys()[0]
            if self.feedforward and self.acceleration_feedforward:
                nf, _ = self.reference_model()
                drive = np.polyadd(np.polymul(nf, dc), nc)        # (F + C / z) z Dc
                characteristic = np.polymul(characteristic, [1.0, 0.0])
            drive = np.polymul(drive, do)
        elif self.feedforward and self.acceleration_feedforward:
            # F = Nf / z and M = Nr / z^2: F + C M = (Nf z Dc + Nc Nr) / (z^2 Dc); the z^2
            # divides the closed loop's numerator, so it multiplies its denominator.
            nf, nr = self.reference_model()
            drive = np.polyadd(np.polymul(np.polymul(nf, [1.0, 0.0]), dc), np.polymul(nc, nr))
            characteristic = np.polymul(characteristic, [1.0, 0.0, 0.0])
        if output == "rim":
            num = np.polymul(np.polymul(drive, self.rim_num), self.meas_den)
            den = np.polymul(self.rim_den, characteristic)
        elif output == "measured":
            num = np.polymul(drive, self.meas_num)
            den = characteristic
        elif output == "voltage":
            num = np.polymul(drive, self.meas_den)
            den = characteristic
        else:
            raise ConfigError(f"closed-loop output {output!r}: valid choices rim, measured, "
                              "voltage")
        return self._tf(num, den)

    def reference_model(self):
        """Numerators of the default form's ``F(z) = Nf / z`` and ``M(z) = Nr / z^2``.

        The controller's nominal wheel ``tau_a du/dt = d - u`` (sampled exactly, decay
        ``a``) is driven to the reference in one period, ``d_k = r_k + A (r_k - u_k)``,
        so ``u_k = r_k-1`` and ``F = g d / r = g ((1 + A) z - A) / z``; its window average
        over the next period, ``c u_k + (1 - c) d_k`` with ``c = tau_a (1 - a) / T``, is
        what the measurement at ``t_k+1`` is compared with:
        ``M = ((1 - c)(1 + A) z + c - (1 - c) A) / z^2``. Both have DC gain 1 (F: ``g``).
        """
        T, tau_a = self.period, self.acceleration_feedforward
        a = math.exp(-T / tau_a)
        big_a = a / (1.0 - a)
        c = tau_a * (1.0 - a) / T
        nf = self.volts_per_speed * np.array([1.0 + big_a, -big_a])
        nr = np.array([(1.0 - c) * (1.0 + big_a), c - (1.0 - c) * big_a])
        return nf, nr

    def continuous_characteristic_in_kp(self, kd):
        """``(base, per_kp)`` of the *continuous* PD loop with no sampling and no delay.

        ``P(s) = Nm/Dm``, ``C(s) = g (kp + kd (e_range/de_range) s / (tau s + 1))``.
        """
        tau, g = self.derivative_time_constant, self.volts_per_speed
        rate_gain = kd * self.e_range / self.de_range
        num, den = self.linear.numerator, self.linear.denominator
        filt = np.array([tau, 1.0])
        base = np.polyadd(np.polymul(filt, den), g * rate_gain * np.polymul([1.0, 0.0], num))
        per_kp = g * np.polymul(filt, num)
        return base, per_kp



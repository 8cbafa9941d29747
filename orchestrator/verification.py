"""The verification report: the sampled wheel-speed loop over the whole fuzzy gain surface.

Model (derived in ``docs/verification.md``): one wheel driving straight without slip, the
voltage-to-rim-speed transfer function of ``docs/plant.md``, held by a zero-order hold over
the speed loop's period ``T`` (20 ms); the measured speed is the exact average of the rim
speed over the last encoder window (what a count difference over ``speed_window`` is, minus
the quantisation); the controller is :class:`components.control.WheelSpeedController`
written as a transfer function at the same period (filtered derivative by backward Euler,
integral accumulated before use). We analyse in discrete time because a continuous PD on the
second-order motor has no finite Routh-Hurwitz gain bound (checked and reported here): the
finite bounds come from the sampling and the measurement's delay, so only a sampled model can
say how far the paper's gains are from them.

Outputs of :func:`verify`: ``verification.json`` (all figures), ``verification.md`` (tables),
and PNG plots (pole map, closed-loop steps, FMU against the transfer function).
"""

import json
import math
import tempfile
import time
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError, SimulationError
from components.control.controller import DEFAULTS as CONTROLLER_DEFAULTS
from components.control.routh import (
    is_hurwitz, is_schur, routh_table, stable_gain_intervals,
)
from components.plant.motor import steady_wheel_speed
from components.plant.parameters import PlantParameters

__all__ = [
    "LinearWheelModel", "WheelLoopModel", "GainAnalysis", "VerificationReport",
    "linear_wheel_model", "analyse_gains", "stability_boundary", "continuous_gain_bound",
    "fmu_step_comparison", "controller_cross_check", "verify", "register_cli",
    "DEFAULT_OUT_DIR",
]

DEFAULT_OUT_DIR = "runs/verify"

# Beyond this kp the search for the stability edge stops. With the defaults the edge is near
# kp = 35, ten times the paper's range; 500 leaves room for other plants and periods.
_KP_SEARCH_MAX = 500.0


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
    """

    inductance: float
    resistance: float
    effective_mass: float
    force_per_current: float
    emf_per_speed: float
    damping: float

    @property
    def numerator(self):
        """Numerator of u/V in s, highest power first."""
        return np.array([self.force_per_current])

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
        b = np.array([[1.0 / L], [0.0]])
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
def _zoh_with_average(a, b, c, period):
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
    extra_delay : int, optional
        Additional whole samples between measurement and voltage: 0 for our Gauss-Seidel
        master (the controller reads the sample the plant finished at ``t_k`` and its voltage
        is held over ``[t_k, t_k + T]``), 1 for a Jacobi master.
    """

    plant: PlantParameters = field(default_factory=PlantParameters)
    period: float = None
    e_range: float = CONTROLLER_DEFAULTS["e_range"]
    de_range: float = CONTROLLER_DEFAULTS["de_range"]
    derivative_time_constant: float = CONTROLLER_DEFAULTS["derivative_time_constant"]
    volts_per_speed: float = CONTROLLER_DEFAULTS["volts_per_speed"]
    feedforward: bool = CONTROLLER_DEFAULTS["feedforward"]
    extra_delay: int = 0

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
        if int(self.extra_delay) != self.extra_delay or self.extra_delay < 0:
            problems.append(f"extra_delay = {self.extra_delay!r} must be an integer >= 0")
        if problems:
            raise ConfigError("verification loop model: " + "; ".join(problems))
        self.linear = linear_wheel_model(self.plant)
        a, b, c = self.linear.state_space()
        ad, bd, average_c, average_d = _zoh_with_average(a, b, c, self.period)
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
    def characteristic_polynomial(self, kp, kd, ki=0.0):
        """``Dc Dm + Nc Nm``: the closed-loop characteristic polynomial in z."""
        nc, dc = self.controller_poly(kp, kd, ki)
        return np.polyadd(np.polymul(dc, self.meas_den), np.polymul(nc, self.meas_num))

    def characteristic_in_kp(self, kd, ki=0.0):
        """``(base, per_kp)`` with characteristic polynomial ``base + kp * per_kp``."""
        base = self.characteristic_polynomial(0.0, kd, ki)
        per_kp = np.polysub(self.characteristic_polynomial(1.0, kd, ki), base)
        return base, per_kp

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
        """Open loop ``C(z) H(z)`` (voltage law times measured-speed path), for margins."""
        nc, dc = self.controller_poly(kp, kd, ki)
        return self._tf(np.polymul(nc, self.meas_num), np.polymul(dc, self.meas_den))

    def closed_loop_tf(self, kp, kd, ki=0.0, output="rim"):
        """Reference -> rim speed (``output="rim"``) or -> measured speed (``"measured"``).

        ``G (F + C) / (1 + C H)`` with ``F = g`` the feedforward (0 if switched off).
        """
        nc, dc = self.controller_poly(kp, kd, ki)
        forward = self.volts_per_speed if self.feedforward else 0.0
        # F + C = (F Dc + Nc) / Dc; 1 + C H = (Dc Dm + Nc Nm) / (Dc Dm).
        drive = np.polyadd(forward * dc, nc)
        characteristic = self.characteristic_polynomial(kp, kd, ki)
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


# ----- analyses -------------------------------------------------------------------------------
@dataclass
class GainAnalysis:
    """Figures of the sampled loop at one gain set."""

    kp: float
    kd: float
    ki: float
    stable_routh: bool
    stable_roots: bool
    spectral_radius: float
    poles: list
    gain_margin: float
    phase_margin_deg: float
    gain_crossover_rad_s: float
    phase_crossover_rad_s: float
    overshoot_pct: float
    rise_time_s: float
    settling_time_s: float
    peak_voltage_per_speed: float
    linear_step_limit_m_s: float


def analyse_gains(model, kp, kd, ki=0.0, duration=1.5, settling_threshold=0.05):
    """Poles, margins and step figures of the sampled loop at one gain set.

    Parameters
    ----------
    model : WheelLoopModel
    kp, kd, ki : float
        Controller gains (``ki`` in 1/s; 0 for PD).
    duration : float, optional
        Length of the step response [s].
    settling_threshold : float, optional
        Settling band as a fraction of the final value (0.05, as in docs/control.md).

    Returns
    -------
    GainAnalysis
        Margins are those of ``C H`` (python-control ``stability_margins``; gain margin as a
        factor, inf when the phase never crosses -180 deg). Step figures are for the true
        rim speed after a reference step (``step_info``); ``peak_voltage_per_speed`` is the
        largest voltage per m/s of reference step, and ``linear_step_limit_m_s`` the largest
        step from rest that stays below ``v_supply`` (the analysis is linear below it).
    """
    import control

    characteristic = model.characteristic_polynomial(kp, kd, ki)
    poles = np.roots(characteristic)
    radius = float(np.max(np.abs(poles)))
    loop = model.loop_tf(kp, kd, ki)
    gm, pm, _, wpc, wgc, _ = control.stability_margins(loop)
    steps = int(round(duration / model.period))
    times = np.arange(steps + 1) * model.period
    rim = control.step_response(model.closed_loop_tf(kp, kd, ki, "rim"), times)
    voltage = control.step_response(model.closed_loop_tf(kp, kd, ki, "voltage"), times)
    stable = radius < 1.0
    if stable:
        info = control.step_info(rim.outputs, times, SettlingTimeThreshold=settling_threshold)
        overshoot, rise, settle = info["Overshoot"], info["RiseTime"], info["SettlingTime"]
    else:
        overshoot = rise = settle = float("nan")
    peak = float(np.max(np.abs(voltage.outputs)))
    return GainAnalysis(
        kp=float(kp), kd=float(kd), ki=float(ki),
        stable_routh=bool(is_schur(characteristic)), stable_roots=stable,
        spectral_radius=radius,
        poles=[[float(p.real), float(p.imag)] for p in poles],
        gain_margin=float(gm), phase_margin_deg=float(pm),
        gain_crossover_rad_s=float(wgc), phase_crossover_rad_s=float(wpc),
        overshoot_pct=float(overshoot), rise_time_s=float(rise), settling_time_s=float(settle),
        peak_voltage_per_speed=peak,
        linear_step_limit_m_s=float(model.plant.v_supply / peak) if peak > 0 else float("inf"),
    )


def _spectral_radius(polynomial):
    return float(np.max(np.abs(np.roots(polynomial))))


def stability_boundary(model, kd, ki=0.0, kp_max=_KP_SEARCH_MAX, samples=500):
    """Largest kp (at fixed kd, ki) for which the sampled loop stays stable, found twice.

    1. Routh-Hurwitz: the characteristic polynomial ``base + kp per_kp`` is mapped to the
       w-plane (``z = (1 + w)/(1 - w)``) and tested with our Routh table
       (:func:`components.control.routh.stable_gain_intervals` with ``is_schur``); the edge
       is bisected on the Routh verdict to 1e-12 relative.
    2. Numeric roots: the same scan on the largest root magnitude, the edge found by Brent's
       method on ``max|z| - 1``.

    Parameters
    ----------
    model : WheelLoopModel
    kd, ki : float
    kp_max : float, optional
        Upper end of the search.
    samples : int, optional
        Scan points on ``[0, kp_max]``.

    Returns
    -------
    dict
        ``kp_routh``, ``kp_roots`` (None when kp = 0 is already unstable; ``kp_max`` when no
        edge was found), ``relative_difference``, ``intervals_routh`` (all stable kp
        intervals in the range), and ``crossing`` (where the critical root leaves the unit
        circle: angle in rad/sample and frequency in Hz; 0 rad means z = +1, pi means -1).
    """
    from scipy.optimize import brentq

    base, per_kp = model.characteristic_in_kp(kd, ki)
    intervals = stable_gain_intervals(base, per_kp, kp_max, test=is_schur, samples=samples)
    kp_routh = intervals[0][1] if intervals and intervals[0][0] == 0.0 else None

    def excess(kp):
        return _spectral_radius(np.polyadd(base, kp * per_kp)) - 1.0

    grid = np.linspace(0.0, kp_max, samples)
    values = np.array([excess(k) for k in grid])
    kp_roots = None
    if values[0] < 0.0:
        above = np.flatnonzero(values >= 0.0)
        if above.size == 0:
            kp_roots = float(kp_max)
        else:
            i = above[0]
            kp_roots = float(brentq(excess, grid[i - 1], grid[i], xtol=1e-14, rtol=1e-14))
    relative = None
    crossing = None
    if kp_routh is not None and kp_roots is not None:
        relative = abs(kp_routh - kp_roots) / max(abs(kp_roots), 1e-300)
        if kp_roots < kp_max:
            roots = np.roots(np.polyadd(base, kp_roots * per_kp))
            critical = roots[np.argmax(np.abs(roots))]
            angle = abs(float(np.angle(critical)))
            crossing = {"angle_rad_per_sample": angle,
                        "frequency_hz": angle / (2 * math.pi * model.period)}
    return {"kd": float(kd), "ki": float(ki), "kp_routh": kp_routh, "kp_roots": kp_roots,
            "relative_difference": relative, "intervals_routh": intervals,
            "crossing": crossing}


def continuous_gain_bound(model, kd, kp_max=1.0e4):
    """Routh on the continuous PD loop (no sampling, no delay): the stable kp intervals.

    Returns
    -------
    dict
        ``intervals`` in ``[0, kp_max]`` and the Routh first column at ``kp_max``, whose
        signs show why no finite bound appears.
    """
    base, per_kp = model.continuous_characteristic_in_kp(kd)
    intervals = stable_gain_intervals(base, per_kp, kp_max, test=is_hurwitz, samples=200)
    column = routh_table(np.polyadd(base, kp_max * per_kp))[:, 0]
    return {"kd": float(kd), "kp_max_searched": float(kp_max), "intervals": intervals,
            "routh_first_column_at_kp_max": [float(v) for v in column]}


def controller_cross_check(model, kp, kd, ki=0.0, step=0.05, samples=40):
    """Run the real :class:`WheelSpeedController` on the sampled linear plant; compare to the TF.

    The controller's derivative starts at zero on its first sample (no kick), so the loop
    runs one sample at zero reference before the step, as it does after any start-up.

    Returns
    -------
    float
        Largest difference [m/s] between the simulated rim speed and the closed-loop
        transfer function's step response (both at the sampling instants).
    """
    import control

    from components.control.controller import WheelSpeedController

    mode = "pid" if ki else "pd"
    controller = WheelSpeedController(
        mode=mode, pd_kp=kp, pd_kd=kd, pid_kp=kp, pid_ki=ki, pid_kd=kd,
        e_range=model.e_range, de_range=model.de_range,
        derivative_time_constant=model.derivative_time_constant,
        volts_per_speed=model.volts_per_speed, feedforward=model.feedforward,
        v_supply=1e9)  # linear comparison: no clipping
    ad, bd, c = model.discrete
    _, _, average_c, average_d = _zoh_with_average(*model.linear.state_space(), model.period)
    state = np.zeros((ad.shape[0], 1))
    delayed = [0.0] * (1 + int(model.extra_delay))  # measurement pipeline
    rim = []
    for k in range(samples + 1):
        reference = step if k >= 1 else 0.0
        measured = delayed[0]
        voltage = controller.step(reference, measured, model.period)
        if k >= 1:
            rim.append((c @ state).item())
        window = (average_c @ state).item() + average_d * voltage
        state = ad @ state + bd * voltage
        delayed = delayed[1:] + [window]
    times = np.arange(samples) * model.period
    reference_tf = control.step_response(model.closed_loop_tf(kp, kd, ki, "rim"), times)
    return float(np.max(np.abs(np.asarray(rim) - step * reference_tf.outputs)))


# ----- the built plant FMU against the transfer function -----------------------------------
def fmu_step_comparison(parameters=None, voltage=2.0, duration=2.0, step=0.02, fmu_dir=None,
                        variants=None):
    """Step the built RobotPlant FMU with a voltage on both wheels; compare with u/V.

    Parameters
    ----------
    parameters : PlantParameters, optional
        Sent to the FMU and used for the transfer function.
    voltage : float, optional
        Step height on both wheels [V] (default 2 V: 0.45 m/s, the tracking speed range).
    duration, step : float, optional
        Length and communication step [s].
    fmu_dir : path-like, optional
        Folder to build into (default: a temporary folder).
    variants : sequence of (str, dict), optional
        Runs as ``(label, parameter overrides)``; default one run, ``("defaults", {})``.
        The transfer function is always that of ``parameters`` (the overrides used by
        :func:`verify` do not enter the linear model: substep and tyre stiffness).

    Returns
    -------
    dict
        Per run: the FMU's ``rim_speed_left`` trace, its largest difference from the TF's step
        response, the time to 63.2 % of the final value and the final value; the TF's trace,
        electrical and mechanical time constants.
    """
    import control

    from orchestrator.build import build_fmu
    from orchestrator.fmu import FmuInstance

    p = parameters or PlantParameters()
    model = linear_wheel_model(p)
    steps = int(round(duration / step))
    times = np.arange(steps + 1) * step
    tf_rim = voltage * control.step_response(model.transfer_function(), times).outputs
    with tempfile.TemporaryDirectory(prefix="sonotrack_verify_") as scratch:
        path = build_fmu("RobotPlant", fmu_dir or scratch)
        runs = []
        for label, overrides in (variants or [("defaults", {})]):
            instance = FmuInstance(path, f"verify_plant_{len(runs)}")
            names = set(instance.variables)
            unknown = sorted(set(overrides) - names)
            if unknown:
                raise ConfigError(f"FMU step comparison {label!r}: RobotPlant has no "
                                  f"parameters {unknown}")
            values = {f.name: getattr(p, f.name) for f in fields(p) if f.name in names}
            values.update(overrides)
            instance.instantiate(0.0, duration, parameters=values)
            try:
                instance.set_values({"voltage_left": voltage, "voltage_right": voltage})
                ports = ["rim_speed_left", "rim_speed_right", "wheel_speed_left", "speed"]
                rows = [instance.get_values(ports)]
                for k in range(steps):
                    instance.do_step(k * step, step)
                    rows.append(instance.get_values(ports))
            except Exception as exc:
                raise SimulationError(f"RobotPlant FMU step test failed: {exc}; "
                                      f"FMU log: {instance.last_error()}") from exc
            finally:
                instance.terminate()
            fmu_rim = np.array([r["rim_speed_left"] for r in rows])
            runs.append({
                "label": label, "overrides": dict(overrides),
                "fmu_rim_speed_left": fmu_rim.tolist(),
                "fmu_wheel_speed_left": [r["wheel_speed_left"] for r in rows],
                "max_abs_difference_m_s": float(np.max(np.abs(fmu_rim - tf_rim))),
                "max_difference_pct_of_final": float(100 * np.max(np.abs(fmu_rim - tf_rim))
                                                     / abs(tf_rim[-1])),
                "left_right_max_difference_m_s": float(np.max(np.abs(
                    fmu_rim - np.array([r["rim_speed_right"] for r in rows])))),
                "fmu_t63_s": _time_to_fraction(times, fmu_rim, 1 - math.exp(-1)),
                "fmu_final_m_s": float(fmu_rim[-1]),
            })
    electrical, mechanical = model.time_constants
    return {
        "voltage_v": float(voltage), "step_s": float(step), "duration_s": float(duration),
        "times": times.tolist(), "tf_rim_speed": tf_rim.tolist(),
        "tf_t63_s": _time_to_fraction(times, tf_rim, 1 - math.exp(-1)),
        "tf_final_m_s": float(tf_rim[-1]),
        "tf_steady_state_m_s": float(voltage * model.dc_gain),
        "electrical_time_constant_s": electrical, "mechanical_time_constant_s": mechanical,
        "runs": runs,
    }


def _time_to_fraction(times, values, fraction):
    """First time the trace reaches ``fraction`` of its steady value (linear interpolation).

    The steady value is the analytic one only for the TF, so both traces use their own last
    sample, which after five time constants is within 1 % of steady.
    """
    target = fraction * values[-1]
    index = int(np.argmax(values >= target))
    if index == 0:
        return float(times[0])
    t0, t1, v0, v1 = times[index - 1], times[index], values[index - 1], values[index]
    return float(t0 + (target - v0) * (t1 - t0) / (v1 - v0))


def _fmu_variants(plant):
    """The FMU runs of the report: defaults, a finer substep, a 100x stiffer tyre.

    The two variants tell integration error from modelling difference: only the former
    shrinks with the substep, only the tyre's compliance shrinks with its stiffness.
    """
    fine = plant.max_substep / 8
    return [("defaults", {}),
            (f"max_substep {1000 * fine:g} ms", {"max_substep": fine}),
            ("slip_stiffness x100", {"slip_stiffness": 100 * plant.slip_stiffness})]


# ----- the report -----------------------------------------------------------------------------
@dataclass
class VerificationReport:
    """Everything :func:`verify` measured, and where it wrote it.

    Attributes
    ----------
    figures : dict
        JSON-ready figures (model, grid, boundaries, PID baseline, FMU comparison, checks).
    paths : dict
        Name -> path of each written file.
    """

    figures: dict
    paths: dict = field(default_factory=dict)

    def to_dict(self):
        """The figures and the written paths as one plain dict."""
        return {"figures": self.figures, "paths": {k: str(v) for k, v in self.paths.items()}}

    def to_json(self, indent=1):
        """The figures as JSON text (NaN and inf written as strings)."""
        return json.dumps(_json_safe(self.figures), indent=indent)

    def summary_lines(self):
        """A few lines for the console."""
        f = self.figures
        grid = f["gain_grid"]
        stable = sum(1 for g in grid if g["stable_routh"])
        lines = [f"gain grid: {stable}/{len(grid)} stable (Routh on the w-plane, "
                 f"agrees with roots at {f['checks']['routh_roots_agreement']} points)"]
        b = f["boundaries_kp"]
        kps = [x["kp_routh"] for x in b if x["kp_routh"] is not None]
        if kps:
            lines.append(f"stability edge: kp {min(kps):.3f}..{max(kps):.3f} over kd "
                         f"{b[0]['kd']:g}..{b[-1]['kd']:g} (paper's kp_max "
                         f"{f['gains']['kp_max']:g}); max Routh/roots relative difference "
                         f"{f['checks']['boundary_max_relative_difference']:.1e}")
        m = f["margins_summary"]
        lines.append(f"margins on the paper's surface: gain {m['gain_margin_min']:.2f}.."
                     f"{m['gain_margin_max']:.2f}, phase {m['phase_margin_min_deg']:.1f}.."
                     f"{m['phase_margin_max_deg']:.1f} deg; overshoot <= "
                     f"{m['overshoot_max_pct']:.2f} %")
        if f.get("fmu_step"):
            run = f["fmu_step"]["runs"][0]
            lines.append(f"FMU vs TF ({f['fmu_step']['voltage_v']:g} V step): max "
                         f"{1000 * run['max_abs_difference_m_s']:.3f} mm/s "
                         f"({run['max_difference_pct_of_final']:.2f} % of final)")
        return lines


def _json_safe(value):
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.floating, np.integer)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def verify(out_dir=DEFAULT_OUT_DIR, plant_parameters=None, controller_parameters=None,
           grid_size=11, period=None, extra_delay=0, fmu=True, step_voltage=2.0, plots=True):
    """Verify the wheel-speed loop over the fuzzy gain surface and write the report.

    Parameters
    ----------
    out_dir : path-like
        Folder for ``verification.json``, ``verification.md`` and the PNG plots.
    plant_parameters : PlantParameters, optional
    controller_parameters : dict, optional
        Overrides of :data:`components.control.DEFAULTS` (gain ranges, PID gains,
        normalisation, derivative filter, volts_per_speed, feedforward).
    grid_size : int, optional
        Points per axis of the kp x kd grid (11: 121 gain sets).
    period : float, optional
        Speed-loop period [s]; default the plant's ``speed_window`` (20 ms).
    extra_delay : int, optional
        Extra samples of delay (1 for a Jacobi master); see :class:`WheelLoopModel`.
    fmu : bool, optional
        Build the RobotPlant FMU and compare its voltage step with the TF.
    step_voltage : float, optional
        Voltage of that step [V].
    plots : bool, optional
        Write the PNG plots.

    Returns
    -------
    VerificationReport
    """
    started = time.perf_counter()
    plant = (plant_parameters or PlantParameters()).validate()
    settings = dict(CONTROLLER_DEFAULTS, **(controller_parameters or {}))
    unknown = sorted(set(controller_parameters or {}) - set(CONTROLLER_DEFAULTS))
    if unknown:
        raise ConfigError(f"verify: unknown controller parameters {unknown}; valid: "
                          f"{sorted(CONTROLLER_DEFAULTS)}")
    if int(grid_size) != grid_size or grid_size < 2:
        raise ConfigError(f"verify: grid_size = {grid_size!r} must be an integer >= 2")
    model = WheelLoopModel(
        plant=plant, period=period, e_range=settings["e_range"], de_range=settings["de_range"],
        derivative_time_constant=settings["derivative_time_constant"],
        volts_per_speed=settings["volts_per_speed"], feedforward=settings["feedforward"],
        extra_delay=extra_delay)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)

    kps = np.linspace(settings["kp_min"], settings["kp_max"], int(grid_size))
    kds = np.linspace(settings["kd_min"], settings["kd_max"], int(grid_size))
    grid = [analyse_gains(model, kp, kd) for kd in kds for kp in kps]
    pid = analyse_gains(model, settings["pid_kp"], settings["pid_kd"], settings["pid_ki"])
    boundaries = [stability_boundary(model, kd) for kd in kds]
    pid_boundary = stability_boundary(model, settings["pid_kd"], settings["pid_ki"])
    kd_edges = []
    for kp in (settings["kp_min"], settings["kp_max"]):
        base, per_kd = model.characteristic_in_kd(kp)
        intervals = stable_gain_intervals(base, per_kd, 200.0, test=is_schur, samples=500)
        kd_edges.append({"kp": float(kp), "intervals_kd_routh": intervals})
    continuous = [continuous_gain_bound(model, kd) for kd in (kds[0], kds[-1])]
    jacobi = None
    if extra_delay == 0:
        jacobi_model = WheelLoopModel(**{**{f.name: getattr(model, f.name)
                                            for f in fields(model)}, "extra_delay": 1})
        jacobi = [stability_boundary(jacobi_model, kd) for kd in (kds[0], kds[-1])]

    mid_kp, mid_kd = float(np.median(kps)), float(np.median(kds))
    cross = {
        "pd_mid": controller_cross_check(model, mid_kp, mid_kd),
        "pid": controller_cross_check(model, settings["pid_kp"], settings["pid_kd"],
                                      settings["pid_ki"]),
    }
    linear = model.linear
    electrical, mechanical = linear.time_constants
    dc_analytic = steady_wheel_speed(1.0, plant) * plant.wheel_radius
    agreement = sum(1 for g in grid if g.stable_routh == g.stable_roots)
    rel = [b["relative_difference"] for b in boundaries + [pid_boundary]
           if b["relative_difference"] is not None]
    stable_grid = [g for g in grid if g.stable_roots]
    figures = {
        "model": {
            "description": ("one wheel, straight line, no slip; ZOH at the loop period; "
                            "measured speed = exact average of the rim speed over the last "
                            "encoder window (one sample late); controller = "
                            "WheelSpeedController as a z-transfer function; no quantisation, "
                            "no voltage limit"),
            "period_s": model.period, "extra_delay_samples": int(extra_delay),
            "effective_mass_kg": linear.effective_mass,
            "force_per_current_n_a": linear.force_per_current,
            "emf_per_speed_v_s_m": linear.emf_per_speed, "damping_n_s_m": linear.damping,
            "inductance_h": linear.inductance, "resistance_ohm": linear.resistance,
            "electrical_time_constant_s": electrical, "mechanical_time_constant_s": mechanical,
            "dc_gain_m_s_per_v": linear.dc_gain, "dc_gain_analytic_m_s_per_v": dc_analytic,
            "volts_per_speed_controller": model.volts_per_speed,
            "measured_tf": {"num": model.meas_num.tolist(), "den": model.meas_den.tolist()},
            "rim_tf": {"num": model.rim_num.tolist(), "den": model.rim_den.tolist()},
        },
        "gains": {k: settings[k] for k in ("kp_min", "kp_max", "kd_min", "kd_max", "pid_kp",
                                           "pid_ki", "pid_kd", "e_range", "de_range",
                                           "derivative_time_constant")},
        "gain_grid": [asdict(g) for g in grid],
        "pid_baseline": asdict(pid),
        "boundaries_kp": boundaries,
        "pid_boundary_kp": pid_boundary,
        "boundaries_kd": kd_edges,
        "continuous_pd": continuous,
        "jacobi_boundaries_kp": jacobi,
        "margins_summary": {
            "gain_margin_min": min(g.gain_margin for g in grid),
            "gain_margin_max": max(g.gain_margin for g in grid),
            "phase_margin_min_deg": min(g.phase_margin_deg for g in grid),
            "phase_margin_max_deg": max(g.phase_margin_deg for g in grid),
            "overshoot_max_pct": max((g.overshoot_pct for g in stable_grid), default=math.nan),
            "settling_max_s": max((g.settling_time_s for g in stable_grid), default=math.nan),
            "spectral_radius_max": max(g.spectral_radius for g in grid),
            "linear_step_limit_min_m_s": min(g.linear_step_limit_m_s for g in grid),
        },
        "checks": {
            "routh_roots_agreement": f"{agreement}/{len(grid)}",
            "boundary_max_relative_difference": max(rel) if rel else None,
            "controller_vs_tf_max_m_s": cross,
            "controller_vs_tf_step_m_s": 0.05,
            "dc_gain_relative_difference": abs(linear.dc_gain - dc_analytic) / dc_analytic,
        },
    }
    if fmu:
        figures["fmu_step"] = fmu_step_comparison(
            plant, voltage=step_voltage, duration=2.0, step=model.period,
            variants=_fmu_variants(plant))
    figures["wall_time_s"] = time.perf_counter() - started

    report = VerificationReport(figures)
    json_path = out_dir / "verification.json"
    json_path.write_text(report.to_json())
    report.paths["json"] = json_path
    if plots:
        report.paths.update(_plots(model, figures, grid, kps, kds, settings, out_dir))
    md_path = out_dir / "verification.md"
    md_path.write_text(_markdown(figures, kps, kds, report.paths))
    report.paths["markdown"] = md_path
    return report


# ----- rendering ------------------------------------------------------------------------------
def _fmt(value, spec=".3g"):
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else ("nan" if math.isnan(value) else "-inf")
    return format(value, spec)


def _grid_table(grid, kps, kds, key, spec):
    by = {(g["kp"], g["kd"]): g for g in grid}
    head = "| kd \\ kp | " + " | ".join(f"{kp:.2f}" for kp in kps) + " |"
    rule = "|---" * (len(kps) + 1) + "|"
    rows = [head, rule]
    for kd in kds:
        cells = []
        for kp in kps:
            g = by[(float(kp), float(kd))]
            cells.append(key(g) if callable(key) else _fmt(g[key], spec))
        rows.append(f"| {kd:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _verdict(f):
    """One paragraph: are the paper's gains stable and well damped in this model?"""
    grid, s, g = f["gain_grid"], f["margins_summary"], f["gains"]
    stable = sum(1 for x in grid if x["stable_routh"])
    edges = [b["kp_routh"] for b in f["boundaries_kp"] if b["kp_routh"] is not None]
    text = [f"{stable} of {len(grid)} frozen gain sets of the paper's surface (kp "
            f"{g['kp_min']:g}..{g['kp_max']:g}, kd {g['kd_min']:g}..{g['kd_max']:g}) are "
            "stable in this model."]
    if stable < len(grid):
        text.append("The paper's gain ranges are NOT all stable here.")
    if edges:
        text.append(f"The nearest kp stability edge, {min(edges):.2f}, is "
                    f"{min(edges) / g['kp_max']:.1f} x kp_max; the smallest gain margin is "
                    f"{s['gain_margin_min']:.2f} ({20 * math.log10(s['gain_margin_min']):.1f} dB) "
                    f"and the smallest phase margin {s['phase_margin_min_deg']:.0f} deg.")
    if s["overshoot_max_pct"] == s["overshoot_max_pct"]:  # not NaN
        damped = "well damped" if s["overshoot_max_pct"] < 5.0 else "poorly damped"
        text.append(f"The linear loop is {damped}: overshoot at most "
                    f"{s['overshoot_max_pct']:.2f} % for a reference step, settling within "
                    f"{s['settling_max_s']:.2f} s. Any overshoot seen in simulation therefore "
                    "comes from what this model leaves out (encoder quantisation, voltage "
                    "saturation, slip, the gain scheduling itself), not from the gains' "
                    "linear stability.")
    return " ".join(text)


def _markdown(f, kps, kds, paths):
    m, c, s = f["model"], f["checks"], f["margins_summary"]
    pid = f["pid_baseline"]
    g = f["gains"]
    lines = [
        "# Wheel-speed loop verification",
        "",
        "Generated by `sonotrack verify` (`orchestrator/verification.py`); how to read it: "
        "`docs/verification.md`.",
        "",
        "## Model",
        "",
        f"- {m['description']}.",
        f"- Plant u/V = K_f / ((L s + R)(M_eff s + B) + K_f K_e): M_eff = "
        f"{m['effective_mass_kg']:.4g} kg, K_f = {m['force_per_current_n_a']:.4g} N/A, "
        f"K_e = {m['emf_per_speed_v_s_m']:.4g} V s/m, B = {m['damping_n_s_m']:.4g} N s/m, "
        f"L = {m['inductance_h']:.3g} H, R = {m['resistance_ohm']:.3g} Ohm.",
        f"- Time constants: electrical {1000 * m['electrical_time_constant_s']:.3f} ms, "
        f"mechanical {m['mechanical_time_constant_s']:.4f} s. DC gain "
        f"{m['dc_gain_m_s_per_v']:.6g} m/s per V; the plant core's analytic steady state "
        f"(`steady_wheel_speed`) gives {m['dc_gain_analytic_m_s_per_v']:.6g} "
        f"(relative difference {c['dc_gain_relative_difference']:.1e}).",
        f"- Sampling period T = {1000 * m['period_s']:.0f} ms; "
        f"extra master delay {m['extra_delay_samples']} sample(s). Controller: "
        f"g = {m['volts_per_speed_controller']:.4f} V s/m, e_range = {g['e_range']} m/s, "
        f"de_range = {g['de_range']} m/s^2, derivative filter tau = "
        f"{g['derivative_time_constant']} s.",
        "- Why discrete time: the continuous PD loop (filtered derivative, no delay) is "
        "third order and Routh finds it stable for every kp searched (below); the finite "
        "bound comes only from the hold and the window-averaged measurement, so the sampled "
        "loop is the one whose bound means something.",
        "",
        "## Verdict",
        "",
        _verdict(f),
        "",
        "## Stability over the gain surface (Routh on the w-plane vs numeric roots)",
        "",
        f"Routh and numeric roots agree at {c['routh_roots_agreement']} grid points. "
        "Cell: largest closed-loop |z| (stable when < 1; `U` marks unstable).",
        "",
        _grid_table(f["gain_grid"], kps, kds,
                    lambda x: _fmt(x["spectral_radius"], ".3f")
                    + ("" if x["stable_routh"] else " U"), None),
        "",
        "## Stability boundary: largest stable kp at fixed kd",
        "",
        "| kd | ki | kp edge (Routh) | kp edge (roots) | relative difference | "
        "critical root leaves at |",
        "|---|---|---|---|---|---|",
    ]
    for b in f["boundaries_kp"] + [f["pid_boundary_kp"]]:
        cross = b["crossing"]
        where = "-" if cross is None else (
            f"{cross['frequency_hz']:.2f} Hz ({cross['angle_rad_per_sample']:.3f} rad/sample)")
        lines.append(f"| {b['kd']:.2f} | {b['ki']:g} | {_fmt(b['kp_routh'], '.6f')} | "
                     f"{_fmt(b['kp_roots'], '.6f')} | {_fmt(b['relative_difference'], '.1e')} "
                     f"| {where} |")
    lines += [
        "",
        f"Largest Routh/roots relative difference: "
        f"{_fmt(c['boundary_max_relative_difference'], '.1e')}.",
        "",
        "Stable kd intervals at fixed kp (Routh): " + "; ".join(
            f"kp = {e['kp']:g}: " + ", ".join(f"[{lo:.4g}, {hi:.4g}]"
                                              for lo, hi in e["intervals_kd_routh"])
            for e in f["boundaries_kd"]) + " (an end at 200 is the end of the search).",
        "",
        "Continuous-time PD (no sampling): " + "; ".join(
            f"kd = {x['kd']:g}: stable kp intervals {x['intervals']} up to "
            f"{x['kp_max_searched']:g}" for x in f["continuous_pd"]) + ".",
    ]
    if f.get("jacobi_boundaries_kp"):
        lines.append("With one more sample of delay (a Jacobi master): kp edge " + ", ".join(
            f"{_fmt(b['kp_routh'], '.3f')} at kd = {b['kd']:g}"
            for b in f["jacobi_boundaries_kp"]) + ".")
    lines += [
        "",
        "## Margins (open loop C(z) H(z))",
        "",
        "Gain margin (factor on the whole controller, python-control `stability_margins`):",
        "",
        _grid_table(f["gain_grid"], kps, kds, "gain_margin", ".2f"),
        "",
        "Phase margin [deg]:",
        "",
        _grid_table(f["gain_grid"], kps, kds, "phase_margin_deg", ".1f"),
        "",
        "## Closed-loop step (reference -> true rim speed, feedforward on)",
        "",
        "Overshoot [%]:",
        "",
        _grid_table(f["gain_grid"], kps, kds, "overshoot_pct", ".2f"),
        "",
        "Settling time into +-5 % [s]:",
        "",
        _grid_table(f["gain_grid"], kps, kds, "settling_time_s", ".3f"),
        "",
        f"Summary over the surface: gain margin {s['gain_margin_min']:.2f}.."
        f"{s['gain_margin_max']:.2f}, phase margin {s['phase_margin_min_deg']:.1f}.."
        f"{s['phase_margin_max_deg']:.1f} deg, overshoot <= {s['overshoot_max_pct']:.2f} %, "
        f"settling <= {s['settling_max_s']:.3f} s, largest |z| {s['spectral_radius_max']:.3f}. "
        f"The analysis is linear: a reference step larger than "
        f"{s['linear_step_limit_min_m_s']:.3f} m/s from rest saturates the voltage at some "
        "gain of the surface (the derivative kick on the first sample is the peak).",
        "",
        "## PID baseline (the paper's CPID)",
        "",
        f"kp = {pid['kp']:g}, ki = {pid['ki']:g} 1/s, kd = {pid['kd']:g}: "
        f"{'stable' if pid['stable_routh'] else 'UNSTABLE'} (largest |z| "
        f"{pid['spectral_radius']:.4f}), gain margin {pid['gain_margin']:.2f}, phase margin "
        f"{pid['phase_margin_deg']:.1f} deg, overshoot {pid['overshoot_pct']:.2f} %, "
        f"settling {pid['settling_time_s']:.3f} s.",
        "",
        "## Cross-checks",
        "",
        f"- The real `WheelSpeedController` run on the sampled linear plant against the "
        f"closed-loop TF ({c['controller_vs_tf_step_m_s']} m/s step): max difference "
        f"{c['controller_vs_tf_max_m_s']['pd_mid']:.2e} m/s (PD, middle of the surface), "
        f"{c['controller_vs_tf_max_m_s']['pid']:.2e} m/s (PID).",
    ]
    fs = f.get("fmu_step")
    if fs:
        lines += [
            "",
            "## Built RobotPlant FMU against the transfer function",
            "",
            f"{fs['voltage_v']:g} V on both wheels from rest, communication step "
            f"{1000 * fs['step_s']:.0f} ms, {fs['duration_s']:g} s, `rim_speed_left` (true "
            f"r w) against the TF's step response. TF: time to 63.2 % "
            f"{fs['tf_t63_s']:.4f} s, final {fs['tf_final_m_s']:.5f} m/s (steady "
            f"{fs['tf_steady_state_m_s']:.5f}).",
            "",
            "| plant run | max abs(FMU - TF) [mm/s] | % of final | FMU t63 [s] | "
            "FMU final [m/s] | left-right max [mm/s] |",
            "|---|---|---|---|---|---|",
        ]
        for run in fs["runs"]:
            lines.append(f"| {run['label']} | "
                         f"{1000 * run['max_abs_difference_m_s']:.3f} | "
                         f"{run['max_difference_pct_of_final']:.3f} | {run['fmu_t63_s']:.4f} | "
                         f"{run['fmu_final_m_s']:.5f} | "
                         f"{1000 * run['left_right_max_difference_m_s']:.2e} |")
        lines += [
            "",
            "Reading: a finer integration substep leaves the difference unchanged, a 100x "
            "stiffer tyre divides it by about 100, so it is the tyre's longitudinal "
            "compliance (the rim runs ahead of the ground by about F d / (c N) while "
            "accelerating), which the rigid no-slip TF leaves out on purpose; the "
            "plant's integration error is far smaller.",
        ]
    lines += [
        "",
        "## Not in this model (honest limits)",
        "",
        "- Encoder quantisation (26 mm/s per count at 20 ms): in closed loop it makes a limit "
        "cycle of about one count, which a linear model cannot show (docs/control.md).",
        "- Voltage saturation at +-v_supply, the PID's anti-windup, and the fuzzy scheduling "
        "itself: each grid point is a *frozen* PD; stability of every frozen gain does not "
        "prove stability of the scheduled (time-varying, nonlinear) loop, though with the "
        "margins above a slow scheduling is very unlikely to destabilise it.",
        "- Turning (each wheel then sees about 1.98 kg instead of 2.44 kg), slip, Coulomb "
        "friction, PWM.",
        "",
        "## Files",
        "",
    ]
    lines += [f"- {name}: `{Path(path).name}`" for name, path in paths.items()]
    lines.append(f"\nWall time: {f['wall_time_s']:.1f} s.")
    return "\n".join(lines) + "\n"


def _plots(model, f, grid, kps, kds, settings, out_dir):
    import control

    from orchestrator.plots import _figure

    plt = _figure()
    written = {}

    fig, ax = plt.subplots(figsize=(6.5, 6))
    theta = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(theta), np.sin(theta), color="0.5", lw=1)
    cmap = plt.get_cmap("viridis")
    for g in grid:
        colour = cmap((g.kd - kds[0]) / max(kds[-1] - kds[0], 1e-12))
        poles = np.array(g.poles)
        ax.plot(poles[:, 0], poles[:, 1], "x", color=colour, ms=4)
    pid = f["pid_baseline"]
    poles = np.array(pid["poles"])
    ax.plot(poles[:, 0], poles[:, 1], "o", mfc="none", color="tab:red", label="PID baseline")
    for b in f["boundaries_kp"][:: max(1, len(kds) - 1)]:
        if b["kp_routh"] is not None and b["crossing"] is not None:
            edge = np.roots(model.characteristic_polynomial(b["kp_routh"], b["kd"]))
            ax.plot(edge.real, edge.imag, "+", color="k", ms=8)
    ax.plot([], [], "+", color="k", label="at the kp stability edge")
    ax.plot([], [], "x", color=cmap(0.0), label=f"grid, kd = {kds[0]:g}")
    ax.plot([], [], "x", color=cmap(1.0), label=f"grid, kd = {kds[-1]:g}")
    ax.set_aspect("equal")
    ax.set_xlabel("Re z")
    ax.set_ylabel("Im z")
    ax.set_title(f"Closed-loop poles over kp {kps[0]:g}..{kps[-1]:g}, kd {kds[0]:g}..{kds[-1]:g}"
                 f" (T = {1000 * model.period:.0f} ms)", fontsize=9)
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    path = out_dir / "pole_map.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written["pole_map"] = path

    fig, ax = plt.subplots(figsize=(7, 4.5))
    times = np.arange(int(round(1.5 / model.period)) + 1) * model.period
    corners = [(kps[0], kds[0]), (kps[-1], kds[0]), (kps[0], kds[-1]), (kps[-1], kds[-1])]
    for kp, kd in corners:
        response = control.step_response(model.closed_loop_tf(kp, kd), times)
        ax.step(times, response.outputs, where="post", label=f"PD kp {kp:g}, kd {kd:g}")
    response = control.step_response(
        model.closed_loop_tf(settings["pid_kp"], settings["pid_kd"], settings["pid_ki"]), times)
    ax.step(times, response.outputs, where="post", ls="--",
            label=f"PID {settings['pid_kp']:g}/{settings['pid_ki']:g}/{settings['pid_kd']:g}")
    ax.axhspan(0.95, 1.05, color="0.9")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("rim speed / reference step")
    ax.set_title("Closed-loop step responses (sampled linear model, feedforward on)",
                 fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    path = out_dir / "step_responses.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written["step_responses"] = path

    fs = f.get("fmu_step")
    if fs:
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True,
                                          gridspec_kw={"height_ratios": [2, 1]})
        t = np.array(fs["times"])
        tf_rim = np.array(fs["tf_rim_speed"])
        top.plot(t, tf_rim, color="k", lw=2, label="transfer function")
        for run in fs["runs"]:
            rim = np.array(run["fmu_rim_speed_left"])
            top.plot(t, rim, "--", label=f"FMU rim_speed_left ({run['label']})")
            bottom.plot(t, 1000 * (rim - tf_rim), label=run["label"])
        top.step(t, fs["runs"][0]["fmu_wheel_speed_left"], where="post", color="0.6", lw=0.8,
                 label="FMU wheel_speed_left (encoder)")
        top.set_ylabel("rim speed [m/s]")
        top.set_title(f"RobotPlant FMU vs u/V, {fs['voltage_v']:g} V step", fontsize=9)
        top.legend(fontsize=8)
        top.grid(alpha=0.3)
        bottom.set_xlabel("time [s]")
        bottom.set_ylabel("FMU - TF [mm/s]")
        bottom.legend(fontsize=8)
        bottom.grid(alpha=0.3)
        path = out_dir / "fmu_vs_tf.png"
        fig.tight_layout()
        fig.savefig(path, dpi=120)
        plt.close(fig)
        written["fmu_vs_tf"] = path
    return written


# ----- command line ---------------------------------------------------------------------------
def _cmd_verify(args):
    report = verify(args.out, grid_size=args.grid, fmu=not args.no_fmu)
    for line in report.summary_lines():
        print(f"  {line}")
    print(f"report: {Path(report.paths['markdown']).resolve()}")
    return 0


def register_cli(subparsers):
    """Add the ``verify`` sub-command to the ``sonotrack`` parser's sub-parsers.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers``; the command calls :func:`verify`.
    """
    command = subparsers.add_parser(
        "verify", help="Routh-Hurwitz and python-control checks of the wheel-speed loop, "
                       "plant FMU vs transfer function")
    command.add_argument("--out", default=DEFAULT_OUT_DIR,
                         help=f"report folder (default: {DEFAULT_OUT_DIR})")
    command.add_argument("--grid", type=int, default=11,
                         help="points per axis of the kp x kd grid (default 11)")
    command.add_argument("--no-fmu", action="store_true",
                         help="skip building the plant FMU and its step comparison")
    command.set_defaults(func=_cmd_verify)
    return command

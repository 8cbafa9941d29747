"""The off-nominal requirements' experiments: references, wheels and what each measures.

Six experiments, one per requirement of ``orchestrator/data/verification_requirements.toml``
(:data:`REQUIREMENTS`): a speed step (settling), a load-torque step (recovery), the planner's
ramp (lag), a stop (creep), a constant speed on the real encoder (limit cycle) and the paper's
trapezoid on a slippery floor (slip chatter). Here live the reference profiles, the wheels
(:func:`plant_variant_parameters`: RobotPlant with its DC gain and mechanical time constant
scaled, exactly the wheel :meth:`.loop_model.LinearWheelModel.scaled` describes) and the
metrics, computed from sampled traces; :mod:`.requirement_runs` runs them on the
discrete-time loop and :mod:`.fmu_requirements` through the FMUs in our master.
"""

import math
from dataclasses import fields, replace

import numpy as np

from components.plant.parameters import PlantParameters

__all__ = ["REQUIREMENTS", "FMU_REQUIREMENTS", "plant_variant_parameters", "step_reference",
           "ramp_reference", "trapezoid", "trapezoid_end", "settling_after",
           "largest_ramp_lag", "creep", "peak_to_peak", "slide_entries", "speed_quantum",
           "judged_cells", "judged_words", "grid_cells"]

# Table names in the requirements file, in the report's order.
REQUIREMENTS = ("off_nominal_settling", "load_step_recovery", "ramp_lag", "no_creep",
                "no_limit_cycle", "no_slip_chatter")
# All six through the FMUs too (the load step as RobotPlant's load_torque fault).
FMU_REQUIREMENTS = REQUIREMENTS


def plant_variant_parameters(gain_factor, time_constant_factor, base=None, **overrides):
    """RobotPlant's parameters for a wheel with its DC gain and time constant multiplied.

    A motor receiving ``G`` times the voltage (the linear model's ``input_gain``) obeys
    ``L di/dt = G V - R i - K_e u``, which divided by ``G`` is the motor with ``L/G``,
    ``R/G`` and ``Ke/G`` at the same current: so those three are divided by ``G``. The
    mechanical time constant follows the effective mass ``m/2 + J_eff / r^2``: mass,
    wheel and rotor inertia (and the yaw inertia, to keep the body's shape) are multiplied by
    ``T``. The tyre's normal load grows with the mass, so slip at a given acceleration is
    unchanged.

    Parameters
    ----------
    gain_factor, time_constant_factor : float
        ``G`` and ``T``.
    base : PlantParameters, optional
        RobotPlant's defaults when None.
    **overrides
        Further parameter values (e.g. ``mu``, ``encoder_ppr``).

    Returns
    -------
    PlantParameters
    """
    p = base or PlantParameters()
    g, t = float(gain_factor), float(time_constant_factor)
    return replace(p, motor_resistance=p.motor_resistance / g,
                   motor_inductance=p.motor_inductance / g,
                   back_emf_constant=p.back_emf_constant / g, mass=p.mass * t,
                   wheel_inertia=p.wheel_inertia * t, rotor_inertia=p.rotor_inertia * t,
                   yaw_inertia=p.yaw_inertia * t, **overrides).validate()


def plant_values(parameters):
    """``PlantParameters`` as a dict of FMU parameter values."""
    return {f.name: getattr(parameters, f.name) for f in fields(parameters)}


def speed_quantum(parameters):
    """One encoder count per speed window [m/s]: ``2 pi r / ppr / speed_window``."""
    return (2.0 * math.pi * parameters.wheel_radius / parameters.encoder_ppr
            / parameters.speed_window)


# ----- references ----------------------------------------------------------------------------
def step_reference(speed, start):
    """``speed`` from ``start`` on, 0 before [m/s]."""
    return lambda t: speed if t >= start - 1e-9 else 0.0


def ramp_reference(speed, acceleration):
    """From 0 at ``acceleration`` up to ``speed``, then held [m/s]."""
    return lambda t: min(speed, acceleration * t)


def trapezoid(speed, acceleration, cruise_time):
    """Up at ``acceleration`` to ``speed``, cruise, down to 0 and held there [m/s]."""
    ramp = speed / acceleration

    def reference(t):
        if t < ramp:
            return acceleration * t
        if t < ramp + cruise_time:
            return speed
        if t < 2.0 * ramp + cruise_time:
            return max(0.0, speed - acceleration * (t - ramp - cruise_time))
        return 0.0
    return reference


def trapezoid_end(speed, acceleration, cruise_time):
    """The time the trapezoid's reference reaches 0 [s]."""
    return 2.0 * speed / acceleration + cruise_time


# ----- metrics -------------------------------------------------------------------------------
def settling_after(t, speed, target, band, start):
    """Time from ``start`` until ``speed`` stays within ``target +- band`` [s].

    The first sample after the last one outside the band, minus ``start``; 0 if none is
    outside; inf if the last sample is.
    """
    t, speed = np.asarray(t), np.asarray(speed)
    outside = np.flatnonzero((np.abs(speed - target) > band) & (t >= start - 1e-9))
    if outside.size == 0:
        return 0.0
    if outside[-1] + 1 >= t.size:
        return math.inf
    return float(t[outside[-1] + 1] - start)


def largest_ramp_lag(t, reference, speed, ramp_end):
    """Largest ``reference - speed`` while the reference ramps (``t <= ramp_end``) [m/s]."""
    t = np.asarray(t)
    on = t <= ramp_end + 1e-9
    return float(np.max(np.asarray(reference)[on] - np.asarray(speed)[on]))


def creep(t, distance, stopped_at, allowance, hold):
    """Travel while the reference is held at 0: ``(creep, overrun)`` [m].

    ``creep`` is ``|distance|`` travelled from ``stopped_at + allowance`` to
    ``stopped_at + allowance + hold``; ``overrun`` the travel in the allowance itself (the
    wheel still stopping).
    """
    def at(time):
        return float(np.interp(time, t, distance))
    begin = stopped_at + allowance
    return abs(at(begin + hold) - at(begin)), abs(at(begin) - at(stopped_at))


def peak_to_peak(t, speed, start):
    """``max - min`` of ``speed`` from ``start`` on [m/s]."""
    t = np.asarray(t)
    return float(np.ptp(np.asarray(speed)[t >= start - 1e-9]))


def slide_entries(t, slip, enter, leave, window=1.0):
    """Entries into sliding and the most of them in any ``window`` seconds.

    A tyre slides from when ``|slip|`` exceeds ``enter`` until it falls below ``leave``
    (hysteresis, so noise at one threshold does not count twice).

    Returns
    -------
    (int, int)
        All entries, and the most entries that start within one window.
    """
    inside, starts = False, []
    for time, value in zip(t, slip):
        if not inside and abs(value) > enter:
            inside = True
            starts.append(time)
        elif inside and abs(value) < leave:
            inside = False
    starts = np.asarray(starts)
    worst = max((int(np.sum((starts >= s) & (starts < s + window - 1e-9))) for s in starts),
                default=0)
    return len(starts), worst


# ----- the grid ------------------------------------------------------------------------------
def grid_cells(grid):
    """Every (gain factor, time-constant factor) of the evaluated grid, gain outer."""
    return [(float(g), float(t)) for g in grid["gain_factors"]
            for t in grid["time_constant_factors"]]


def judged_cells(grid):
    """The cells the verdicts are given on: every cell of the grid, or, with
    ``judged_factor_span`` in the grid table, those whose gain, time constant and their ratio
    all lie within ``x1/span .. x span``."""
    if "judged_factor_span" not in grid:
        return grid_cells(grid)
    span = float(grid["judged_factor_span"])

    def inside(x):
        return 1.0 / span - 1e-9 <= x <= span + 1e-9
    return [(g, t) for g, t in grid_cells(grid) if inside(g) and inside(t) and inside(g / t)]


def judged_words(grid):
    """Which wheels are judged, in words (for reports)."""
    if "judged_factor_span" not in grid:
        return "every wheel of the grid"
    span = float(grid["judged_factor_span"])
    return f"the wheels whose gain, time constant and gain/tau lie within x{1 / span:g}..x{span:g}"

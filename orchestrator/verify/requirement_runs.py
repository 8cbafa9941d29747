"""The off-nominal requirements on the discrete-time loop, over the whole grid of wheels.

Each experiment of :mod:`.wheel_experiments` runs the real
:class:`components.control.WheelSpeedController` of one design on one wheel: the sampled
linear wheel (:class:`.sampled_wheel.SampledWheel`, exact at the loop period, with the load
torque and, where the requirement says so, the encoder's counts) for five of them, and the
RobotPlant core itself (traction, slip, encoders; scaled by
:func:`.wheel_experiments.plant_variant_parameters`) for slip chatter, which a linear wheel
cannot show. :func:`measure_requirements` returns, per requirement and cell, the measured
value and whether it holds.
"""

import math

import numpy as np

from components.control.controller import WheelSpeedController
from components.plant import RobotPlantCore

from . import wheel_experiments as X
from .loop_model import linear_wheel_model
from .sampled_wheel import SampledWheel, run_loop, stall_force

__all__ = ["measure_requirements", "run_model_experiment", "EXPERIMENTS"]


def _wheel(plant, cell, quantised):
    linear = linear_wheel_model(plant).scaled(*cell)
    return SampledWheel(linear, plant.speed_window,
                        plant.encoder_ppr if quantised else None, plant.wheel_radius,
                        plant.v_supply)


def settling(settings, plant, cell, req, grid):
    """Settling time into +-band of a speed step, no quantisation [s]."""
    start = plant.speed_window
    speed = req["step_m_s"]
    trace = run_loop(WheelSpeedController(**settings), _wheel(plant, cell, False),
                     X.step_reference(speed, start), req["run_time_s"])
    value = X.settling_after(trace.t, trace.rim_speed, speed, req["band_fraction"] * speed,
                             start)
    return {"value": value, "passed": value <= req["max_settling_time_s"]}


def load_recovery(settings, plant, cell, req, grid):
    """Recovery into +-band after a load-torque step of a fraction of the stall torque [s]."""
    wheel = _wheel(plant, cell, False)
    force = req["load_fraction_of_stall"] * stall_force(linear_wheel_model(plant).scaled(*cell),
                                                        plant.v_supply)
    speed, start = req["speed_m_s"], req["load_time_s"]
    trace = run_loop(WheelSpeedController(**settings), wheel,
                     X.step_reference(speed, plant.speed_window), req["run_time_s"],
                     load=lambda t: force if t >= start - 1e-9 else 0.0)
    value = X.settling_after(trace.t, trace.rim_speed, speed, req["band_fraction"] * speed,
                             start)
    return {"value": value, "passed": value <= req["max_recovery_time_s"],
            "load_force_n": force}


def ramp_lag(settings, plant, cell, req, grid):
    """Largest lag of the true rim speed behind the planner's ramp, real encoder [m/s]."""
    speed, acceleration = req["speed_m_s"], req["acceleration_m_s2"]
    trace = run_loop(WheelSpeedController(**settings), _wheel(plant, cell, True),
                     X.ramp_reference(speed, acceleration), req["run_time_s"])
    value = X.largest_ramp_lag(trace.t, trace.reference, trace.rim_speed,
                               speed / acceleration)
    overshoot = float(np.max(trace.rim_speed) - speed)
    bound = acceleration * req["fix_period_s"]
    return {"value": value, "passed": value <= bound, "overshoot_m_s": overshoot}


def no_creep(settings, plant, cell, req, grid):
    """Travel while the reference is held at zero after a stop, real encoder [m]."""
    speed, acceleration, cruise = req["speed_m_s"], req["acceleration_m_s2"], req["cruise_time_s"]
    stopped = X.trapezoid_end(speed, acceleration, cruise)
    allowance, hold = req["settle_allowance_s"], req["hold_time_s"]
    trace = run_loop(WheelSpeedController(**settings), _wheel(plant, cell, True),
                     X.trapezoid(speed, acceleration, cruise), stopped + allowance + hold)
    value, overrun = X.creep(trace.t, trace.distance, stopped, allowance, hold)
    return {"value": value, "passed": value < req["max_creep_m"], "overrun_m": overrun}


def no_limit_cycle(settings, plant, cell, req, grid):
    """Peak-to-peak true speed at a constant reference, in encoder speed quanta [1]."""
    speed, acceleration = req["speed_m_s"], req["acceleration_m_s2"]
    trace = run_loop(WheelSpeedController(**settings), _wheel(plant, cell, True),
                     X.ramp_reference(speed, acceleration), req["run_time_s"])
    value = (X.peak_to_peak(trace.t, trace.rim_speed, req["run_time_s"] - req["window_s"])
             / X.speed_quantum(plant))
    return {"value": value, "passed": value < req["max_peak_to_peak_quanta"]}


def no_slip_chatter(settings, plant, cell, req, grid):
    """Most slide entries in one second over the frictions, both wheels (RobotPlant core)."""
    worst, at = 0, None
    per_friction = {}
    for mu in grid["frictions"]:
        parameters = X.plant_variant_parameters(*cell, base=plant, mu=float(mu))
        core = RobotPlantCore(parameters)
        left, right = WheelSpeedController(**settings), WheelSpeedController(**settings)
        reference = X.trapezoid(req["speed_m_s"], req["acceleration_m_s2"], req["cruise_time_s"])
        h = parameters.speed_window
        steps = int(round((X.trapezoid_end(req["speed_m_s"], req["acceleration_m_s2"],
                                           req["cruise_time_s"]) + req["tail_s"]) / h))
        slips = np.zeros((steps, 2))
        for k in range(steps):
            r = reference(k * h)
            core.step(left.step(r, core.wheel_speed_left, h),
                      right.step(r, core.wheel_speed_right, h), h)
            slips[k] = (core.slip_left, core.slip_right)
        count = _chatter(np.arange(1, steps + 1) * h, slips, mu, parameters, req)
        per_friction[f"{float(mu):g}"] = count
        if at is None or count > worst:
            worst, at = count, float(mu)
    return {"value": worst, "passed": worst <= req["max_entries_per_second"],
            "at_friction": at, "per_friction": per_friction}


def _chatter(t, slips, mu, parameters, req):
    """Most slide entries in one second of either wheel (thresholds in units of mu / c)."""
    unit = mu / parameters.slip_stiffness
    return max(X.slide_entries(t, slips[:, side], req["enter_slip_factor"] * unit,
                               req["leave_slip_factor"] * unit)[1] for side in (0, 1))


EXPERIMENTS = {"off_nominal_settling": settling, "load_step_recovery": load_recovery,
               "ramp_lag": ramp_lag, "no_creep": no_creep, "no_limit_cycle": no_limit_cycle,
               "no_slip_chatter": no_slip_chatter}


def run_model_experiment(name, settings, plant, cell, req, grid):
    """One requirement's experiment on one wheel; ``{"value", "passed", ...}``."""
    result = EXPERIMENTS[name](settings, plant, cell, req[name], grid)
    value = result["value"]
    result["value"] = float(value) if math.isfinite(value) else math.inf
    result["passed"] = bool(result["passed"])
    return result


def measure_requirements(settings, plant, req, cells=None, commission=True):
    """Every off-nominal requirement on every cell of the grid (or ``cells``).

    Parameters
    ----------
    settings : dict
        One design's controller parameters.
    plant : PlantParameters
        RobotPlant's (the grid scales it).
    req : dict
        The requirements file's tables (``off_nominal_grid``, ``commissioning`` and the six
        of :data:`.wheel_experiments.REQUIREMENTS`).
    cells : list of (float, float), optional
        Default: the whole evaluated grid.
    commission : bool, optional
        Commission the controller on each wheel first (:mod:`.commissioning`; the
        ``commissioning`` table must be there); False: ``settings`` as they are.

    Returns
    -------
    dict
        Requirement -> list of ``{"gain_factor", "time_constant_factor", "value",
        "passed", ...}``; commissioned rows carry the constants found
        (``commissioned_volts_per_speed``, ``commissioned_time_constant``).
    """
    from .commissioning import commission_model, commissioned

    grid = req["off_nominal_grid"]
    cells = X.grid_cells(grid) if cells is None else cells
    per_cell, extra = {}, {}
    for cell in cells:
        per_cell[cell], extra[cell] = settings, {}
        if commission:
            fit = commission_model(plant, cell, req["commissioning"])
            per_cell[cell] = commissioned(settings, fit)
            extra[cell] = {"commissioned_volts_per_speed": fit.volts_per_speed,
                           "commissioned_time_constant": fit.time_constant}
    return {name: [dict(run_model_experiment(name, per_cell[cell], plant, cell, req, grid),
                        gain_factor=cell[0], time_constant_factor=cell[1], **extra[cell])
                   for cell in cells]
            for name in X.REQUIREMENTS}

"""Commissioning each wheel before it is judged: its two constants from a voltage step.

A controller tuned for RobotPlant's wheel (``volts_per_speed`` 4.44 V s/m, mechanical time
constant 0.39 s) drives a wheel with four times the gain or a fifth of the time constant
badly, whatever its gains (docs/verification.md, "the whole grid"); a drive is therefore
commissioned on the wheel it will drive. Here the experiment of
``[commissioning]`` in the requirements file (a constant voltage from rest, the encoder's
position every period) runs on the wheel being judged -- the sampled linear wheel with the
real encoder for the discrete-time loop, RobotPlant's FMU through our master for the FMU
runs -- and :func:`components.control.identification.fit_step_response` gives its
constants. :func:`commissioned` puts them into a design's parameters: ``volts_per_speed``
into every design (the feedforward of all three reads it), ``acceleration_feedforward``
(also the speed observer's model) into the default form only (the other forms refuse it).
"""

import math

from components.control.identification import fit_step_response

from .designs import is_default_form

__all__ = ["commission_model", "commission_fmu", "commissioned", "VOLTAGE_SOURCE"]

# WheelController as a voltage source: the paper form's pure PD with zero gains and the
# feedforward at 1 V per (m/s), so that its voltage is its reference.
VOLTAGE_SOURCE = {"mode": "pd", "form": "paper", "pd_kp": 0.0, "pd_kd": 0.0, "trim_ki": 0.0,
                  "feedforward": True, "volts_per_speed": 1.0}


def _fit(times, positions, table):
    return fit_step_response(times, positions, float(table["voltage_v"]))


def commission_model(plant, cell, table):
    """The step experiment on the sampled wheel of ``cell`` with RobotPlant's encoder.

    Parameters
    ----------
    plant : PlantParameters
        RobotPlant's (the cell scales it).
    cell : (float, float)
        (gain factor, time-constant factor).
    table : dict
        ``[commissioning]``: ``voltage_v``, ``duration_s``.

    Returns
    -------
    StepFit
    """
    from .loop_model import linear_wheel_model
    from .sampled_wheel import SampledWheel

    wheel = SampledWheel(linear_wheel_model(plant).scaled(*cell), plant.speed_window,
                         plant.encoder_ppr, plant.wheel_radius, plant.v_supply)
    steps = int(round(table["duration_s"] / plant.speed_window))
    times, positions, position = [], [], 0.0
    for k in range(1, steps + 1):
        position += wheel.step(table["voltage_v"]) * plant.speed_window
        times.append(k * plant.speed_window)
        positions.append(position)
    return _fit(times, positions, table)


def commission_fmu(loop, plant_parameters, table):
    """The step experiment through the FMUs: RobotPlant (both wheels at the voltage, driving
    straight) and its left encoder's count, read by our master every period.

    Parameters
    ----------
    loop : FmuLoop
    plant_parameters : PlantParameters
        The wheel's (already scaled).
    table : dict
        ``[commissioning]``.

    Returns
    -------
    StepFit
    """
    voltage = float(table["voltage_v"])
    run = loop.run(VOLTAGE_SOURCE, plant_parameters, lambda t: voltage, table["duration_s"])
    per_count = 2.0 * math.pi * plant_parameters.wheel_radius / plant_parameters.encoder_ppr
    return _fit(run["t"][1:], run["encoder_left"][1:] * per_count, table)


def commissioned(settings, fit):
    """``settings`` with the wheel's constants each design reads (see the module docstring)."""
    out = dict(settings, volts_per_speed=fit.volts_per_speed)
    if is_default_form(settings):
        out["acceleration_feedforward"] = fit.time_constant
    return out

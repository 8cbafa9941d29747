"""The off-nominal requirements through the built FMUs in our master.

RobotPlant (its parameters scaled by :func:`.wheel_experiments.plant_variant_parameters`,
so the wheel is the grid's) and two WheelController FMUs of one design, connected as in the
system (``voltage`` -> ``voltage_left/right``, ``wheel_speed_left/right`` -> ``v_meas``) and
stepped by :class:`orchestrator.run.master.Master`, Gauss-Seidel, controllers first, at the
speed window; the reference is written to both controllers' ``v_ref`` before each step.
Every experiment of :data:`.wheel_experiments.FMU_REQUIREMENTS` runs on each judged cell;
the load step is RobotPlant's own ``load_torque`` fault (its ``fault_schedule`` parameter,
docs/faults.md) on both wheels. The FMU instances are reused between runs (``fmi2Reset``).
"""

import math
import tempfile

import numpy as np

from components.common.errors import SimulationError
from components.common.faults import Fault, encode_schedule

from . import wheel_experiments as X

__all__ = ["fmu_requirements", "FmuLoop"]

# The settling run's encoder: fine enough that its quantum (2 pi 0.06 / 1e6 / 0.02 = 19 um/s)
# is far below the 6 mm/s band; the other runs keep RobotPlant's 728 counts.
FINE_ENCODER_PPR = 1_000_000


class FmuLoop:
    """RobotPlant + two WheelController FMUs, reusable across runs.

    Parameters
    ----------
    plant_path, controller_path : path-like
        The built FMUs.
    """

    def __init__(self, plant_path, controller_path):
        from orchestrator.fmu.handle import FmuInstance

        self.plant = FmuInstance(plant_path, "verify_requirements_plant", reusable=True)
        self.controllers = {side: FmuInstance(controller_path, f"verify_requirements_{side}",
                                              reusable=True) for side in ("left", "right")}

    def run(self, controller_parameters, plant_parameters, reference, duration,
            fault_schedule=""):
        """One run from rest; the plant's outputs after every step.

        ``fault_schedule`` is RobotPlant's (a JSON list, docs/faults.md; "" none).

        Returns
        -------
        dict
            ``t`` (0, T, 2T, ...), ``reference``, ``rim_left``, ``rim_right``,
            ``slip_left``, ``slip_right``, ``encoder_left`` (counts) as arrays.
        """
        from orchestrator.run.master import InstanceSpec, Link, Master

        period = plant_parameters.speed_window
        steps = int(round(duration / period))
        values = X.plant_values(plant_parameters)
        plant_values = {k: v for k, v in values.items() if k in self.plant.variables}
        plant_values["fault_schedule"] = fault_schedule
        specs = [InstanceSpec(side, handle, parameters={
                     k: v for k, v in controller_parameters.items() if k in handle.variables})
                 for side, handle in self.controllers.items()]
        specs.append(InstanceSpec("plant", self.plant, parameters=plant_values))
        links = [Link(f"{side}.voltage", f"plant.voltage_{side}") for side in ("left", "right")]
        links += [Link(f"plant.wheel_speed_{side}", f"{side}.v_meas")
                  for side in ("left", "right")]
        master = Master(specs, links, period)
        master.initialize(0.0, (steps + 1) * period)
        reals = master.output_group("plant", "Real", ["rim_speed_left", "rim_speed_right",
                                                      "slip_left", "slip_right"])
        counts = master.output_group("plant", "Integer", ["encoder_left"])
        inputs = [handle.port_group("Real", ["v_ref"]) for handle in self.controllers.values()]
        rows = np.zeros((steps + 1, 7))
        try:
            for k in range(steps):
                r = reference(k * period)
                for group, handle in zip(inputs, self.controllers.values()):
                    group.values[0] = r
                    handle.write(group)
                master.step(k)
                rows[k, 0] = r
                rows[k + 1, 1:5] = master.read_outputs("plant", reals)
                rows[k + 1, 5] = master.read_outputs("plant", counts)[0]
            rows[steps, 0] = reference(steps * period)
        except Exception as exc:
            raise SimulationError(f"off-nominal FMU run failed at step {k}: {exc}; FMU log: "
                                  f"{self.plant.last_error() or ''}") from exc
        finally:
            master.terminate()
        rows[:, 6] = np.arange(steps + 1) * period
        return {"t": rows[:, 6], "reference": rows[:, 0], "rim_left": rows[:, 1],
                "rim_right": rows[:, 2], "slip_left": rows[:, 3], "slip_right": rows[:, 4],
                "encoder_left": rows[:, 5]}

    def release(self):
        """Free the FMU instances."""
        for handle in (self.plant, *self.controllers.values()):
            handle.release()


def _settling(loop, settings, plant, cell, req, grid):
    parameters = X.plant_variant_parameters(*cell, base=plant, encoder_ppr=FINE_ENCODER_PPR)
    start, speed = plant.speed_window, req["step_m_s"]
    run = loop.run(settings, parameters, X.step_reference(speed, start), req["run_time_s"])
    value = X.settling_after(run["t"], run["rim_left"], speed, req["band_fraction"] * speed,
                             start)
    return {"value": value, "passed": value <= req["max_settling_time_s"]}


def _load_recovery(loop, settings, plant, cell, req, grid):
    """The load step as RobotPlant's load_torque fault: the same torque the loop's
    :func:`.requirement_runs.load_recovery` applies as a rim force, on both wheels."""
    from .loop_model import linear_wheel_model
    from .sampled_wheel import stall_force

    parameters = X.plant_variant_parameters(*cell, base=plant, encoder_ppr=FINE_ENCODER_PPR)
    force = req["load_fraction_of_stall"] * stall_force(linear_wheel_model(plant).scaled(*cell),
                                                        plant.v_supply)
    speed, start = req["speed_m_s"], req["load_time_s"]
    schedule = encode_schedule([Fault("load_torque", float(start),
                                      magnitude=force * parameters.wheel_radius,
                                      channel="both")])
    run = loop.run(settings, parameters, X.step_reference(speed, plant.speed_window),
                   req["run_time_s"], fault_schedule=schedule)
    value = X.settling_after(run["t"], run["rim_left"], speed, req["band_fraction"] * speed,
                             start)
    return {"value": value, "passed": value <= req["max_recovery_time_s"],
            "load_torque_n_m": force * parameters.wheel_radius}


def _ramp_lag(loop, settings, plant, cell, req, grid):
    speed, acceleration = req["speed_m_s"], req["acceleration_m_s2"]
    run = loop.run(settings, X.plant_variant_parameters(*cell, base=plant),
                   X.ramp_reference(speed, acceleration), req["run_time_s"])
    value = X.largest_ramp_lag(run["t"], run["reference"], run["rim_left"],
                               speed / acceleration)
    return {"value": value, "passed": value <= acceleration * req["fix_period_s"],
            "overshoot_m_s": float(np.max(run["rim_left"]) - speed)}


def _creep(loop, settings, plant, cell, req, grid):
    speed, acceleration, cruise = req["speed_m_s"], req["acceleration_m_s2"], req["cruise_time_s"]
    stopped = X.trapezoid_end(speed, acceleration, cruise)
    allowance, hold = req["settle_allowance_s"], req["hold_time_s"]
    parameters = X.plant_variant_parameters(*cell, base=plant)
    run = loop.run(settings, parameters, X.trapezoid(speed, acceleration, cruise),
                   stopped + allowance + hold)
    # the encoder's count (floor of the wheel angle) is the travel to within one count
    distance = run["encoder_left"] * 2.0 * math.pi * parameters.wheel_radius / \
        parameters.encoder_ppr
    value, overrun = X.creep(run["t"], distance, stopped, allowance, hold)
    return {"value": value, "passed": value < req["max_creep_m"], "overrun_m": overrun}


def _limit_cycle(loop, settings, plant, cell, req, grid):
    speed, acceleration = req["speed_m_s"], req["acceleration_m_s2"]
    parameters = X.plant_variant_parameters(*cell, base=plant)
    run = loop.run(settings, parameters, X.ramp_reference(speed, acceleration),
                   req["run_time_s"])
    value = (X.peak_to_peak(run["t"], run["rim_left"], req["run_time_s"] - req["window_s"])
             / X.speed_quantum(parameters))
    return {"value": value, "passed": value < req["max_peak_to_peak_quanta"]}


def _slip_chatter(loop, settings, plant, cell, req, grid):
    speed, acceleration, cruise = req["speed_m_s"], req["acceleration_m_s2"], req["cruise_time_s"]
    worst, at, per_friction = 0, None, {}
    for mu in grid["frictions"]:
        parameters = X.plant_variant_parameters(*cell, base=plant, mu=float(mu))
        run = loop.run(settings, parameters, X.trapezoid(speed, acceleration, cruise),
                       X.trapezoid_end(speed, acceleration, cruise) + req["tail_s"])
        unit = float(mu) / parameters.slip_stiffness
        count = max(X.slide_entries(run["t"], run[f"slip_{side}"],
                                    req["enter_slip_factor"] * unit,
                                    req["leave_slip_factor"] * unit)[1]
                    for side in ("left", "right"))
        per_friction[f"{float(mu):g}"] = count
        if at is None or count > worst:
            worst, at = count, float(mu)
    return {"value": worst, "passed": worst <= req["max_entries_per_second"],
            "at_friction": at, "per_friction": per_friction}


_RUNS = {"off_nominal_settling": _settling, "load_step_recovery": _load_recovery,
         "ramp_lag": _ramp_lag, "no_creep": _creep,
         "no_limit_cycle": _limit_cycle, "no_slip_chatter": _slip_chatter}


def fmu_requirements(designs, plant, req, cells, fmu_dir=None, commission=True):
    """The FMU experiments of every design on ``cells``, each design commissioned on each
    wheel through the FMUs first (:func:`.commissioning.commission_fmu`; ``commission``
    False: the designs' parameters as they are).

    Parameters
    ----------
    designs : dict
        Design name -> controller parameters.
    plant : PlantParameters
    req : dict
        The requirements file's tables.
    cells : list of (float, float)
        (gain factor, time-constant factor) of the wheels.
    fmu_dir : path-like, optional
        Folder holding the built FMUs, or to build them into (default: a temporary one).

    Returns
    -------
    dict
        Design -> requirement -> list of ``{"gain_factor", "time_constant_factor",
        "value", "passed", ...}``.
    """
    from .fmu_runs import built_fmu

    from .commissioning import commission_fmu, commissioned

    grid = req["off_nominal_grid"]
    results = {}
    with tempfile.TemporaryDirectory(prefix="sonotrack_verify_") as scratch:
        folder = fmu_dir or scratch
        loop = FmuLoop(built_fmu("RobotPlant", folder), built_fmu("WheelController", folder))
        try:
            fits = {cell: commission_fmu(loop, X.plant_variant_parameters(*cell, base=plant),
                                         req["commissioning"])
                    for cell in cells} if commission else {}
            for design, settings in designs.items():
                results[design] = {}
                for name in X.FMU_REQUIREMENTS:
                    rows = []
                    for cell in cells:
                        own = commissioned(settings, fits[cell]) if commission else settings
                        result = _RUNS[name](loop, own, plant, cell, req[name], grid)
                        value = result["value"]
                        result.update(value=float(value) if math.isfinite(value) else math.inf,
                                      passed=bool(result["passed"]), gain_factor=cell[0],
                                      time_constant_factor=cell[1])
                        rows.append(result)
                    results[design][name] = rows
        finally:
            loop.release()
    return results

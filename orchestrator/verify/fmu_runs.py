"""The built FMUs against the models the analyses use.

- :func:`fmu_step_comparison`: RobotPlant FMU, voltage step, against the wheel's u/V.
- :func:`controller_fmu_comparison`: WheelController FMU, random inputs, against the law
  recomputed independently here.
- :func:`closed_loop_fmu_comparison`: RobotPlant + WheelController FMUs connected and run by
  :class:`orchestrator.run.master.Master` at the loop's period, against the closed-loop TF.
"""

import math
import tempfile
from dataclasses import fields
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError, SimulationError
from components.plant.parameters import PlantParameters

from .designs import is_default_form, loop_gains, loop_model
from .loop_model import linear_wheel_model

__all__ = ["fmu_step_comparison", "fmu_variants", "compliance_bound",
           "controller_fmu_comparison", "controller_law_reference",
           "closed_loop_fmu_comparison", "built_fmu"]


def built_fmu(name, folder):
    """``folder / <name>.fmu``, built there first unless it is there already.

    :func:`.report.verify` builds each FMU once, before any is loaded, and hands the folder
    to every comparison: building again in a process that has loaded an FMU of the same
    model fails (pythonfmu finds the loaded model's module under the model's name).
    """
    from orchestrator.builder.fmus import build_fmu

    path = Path(folder) / f"{name}.fmu"
    return path if path.is_file() else build_fmu(name, folder)


def compliance_bound(parameters, voltage):
    """Largest rim-minus-ground speed the tyre's compliance can add in a voltage step [m/s].

    The TF is rigid (rim speed = ground speed). The plant's tyre transmits ``F = c N s`` with
    slip ``s = (rim - ground) / d``, ``d <= |rim|``, so ``rim - ground <= F |rim| / (c N)``.
    The rim force is largest at the start, ``F <= (m/2) a0`` with ``a0 = v_final / tau``, and
    ``|rim| <= v_final``: the bound is ``(m/2) v_final^2 / (tau c N)`` (5.3 mm/s at 2 V).
    """
    linear = linear_wheel_model(parameters)
    v_final = voltage * linear.dc_gain
    _, tau = linear.time_constants
    normal = 0.5 * parameters.mass * parameters.gravity
    return 0.5 * parameters.mass * v_final ** 2 / (tau * parameters.slip_stiffness * normal)


def fmu_step_comparison(parameters=None, voltage=2.0, duration=2.0, step=0.02, fmu_dir=None,
                        variants=None, fmu_overrides=None):
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
        Folder holding the built FMUs, or to build them into (:func:`built_fmu`; default: a
        temporary folder).
    variants : sequence of (str, dict), optional
        Runs as ``(label, parameter overrides)``; default one run, ``("defaults", {})``.
        The transfer function is always that of ``parameters`` (the overrides used by
        :func:`verify` do not enter the linear model: substep and tyre stiffness).
    fmu_overrides : dict, optional
        Parameters given to the FMU in every run but not to the TF (a deliberately different
        plant, e.g. another ``motor_resistance``, for the tests that the check can fail).

    Returns
    -------
    dict
        Per run: the FMU's ``rim_speed_left`` trace, its largest difference from the TF's step
        response, the time to 63.2 % of the final value and the final value; the TF's trace,
        electrical and mechanical time constants.
    """
    import control

    from orchestrator.fmu.handle import FmuInstance

    p = parameters or PlantParameters()
    model = linear_wheel_model(p)
    steps = int(round(duration / step))
    times = np.arange(steps + 1) * step
    tf_rim = voltage * control.step_response(model.transfer_function(), times).outputs
    with tempfile.TemporaryDirectory(prefix="sonotrack_verify_") as scratch:
        path = built_fmu("RobotPlant", fmu_dir or scratch)
        runs = []
        for label, overrides in (variants or [("defaults", {})]):
            instance = FmuInstance(path, f"verify_plant_{len(runs)}")
            names = set(instance.variables)
            unknown = sorted(set(overrides) - names)
            if unknown:
                raise ConfigError(f"FMU step comparison {label!r}: RobotPlant has no "
                                  f"parameters {unknown}")
            values = {f.name: getattr(p, f.name) for f in fields(p) if f.name in names}
            values.update(fmu_overrides or {})
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


def fmu_variants(plant):
    """The FMU runs of the report: defaults, a finer substep, a 100x stiffer tyre.

    The two variants tell integration error from modelling difference: only the former
    shrinks with the substep, only the tyre's compliance shrinks with its stiffness.
    """
    fine = plant.max_substep / 8
    return [("defaults", {}),
            (f"max_substep {1000 * fine:g} ms", {"max_substep": fine}),
            ("slip_stiffness x100", {"slip_stiffness": 100 * plant.slip_stiffness})]




# ----- WheelController FMU against the law ----------------------------------------------------
def controller_law_reference(settings, inputs, h):
    """The documented controller law (docs/control.md), recomputed here step by step.

    Independent of :class:`components.control.WheelSpeedController` except for the fuzzy
    scheduler's normalised gains (the scheduler is checked against scikit-fuzzy in the unit
    tests): its own backward-Euler derivative, integrator with conditional integration and
    clamp, feedforward, the default form's reference model, speed observer and reset, and
    clipping.

    Parameters
    ----------
    settings : dict
        Controller parameters (:data:`components.control.DEFAULTS` with overrides).
    inputs : sequence of (v_ref, v_meas)
    h : float
        Step [s].

    Returns
    -------
    list of (voltage, kp, kd, e_n, de_n)
        ``e_n``, ``de_n``: the scheduler's inputs (outside [-1, 1]: outside its universe).
    """
    from components.control.inference import FuzzyGainScheduler

    s = settings
    default = s.get("form", "default") == "default" and s["mode"] != "pid"
    g, limit = s["volts_per_speed"], s["v_supply"]
    tau = s["derivative_time_constant"]
    e_scale, de_scale = ((s["fuzzy_e_range"], s["fuzzy_de_range"]) if default
                         else (s["e_range"], s["de_range"]))
    scheduler = FuzzyGainScheduler(e_scale, de_scale, method=s["fuzzy_method"])
    ki = (s["pid_ki"] if s["mode"] == "pid"
          else s["integral_gain"] if default else s["trim_ki"])
    # the integral term's voltage per unit of the integral, and its clamp
    per_integral = g * ki if default else g * s["e_range"] * ki
    integral, rate, previous = 0.0, 0.0, None
    model_speed, model_window = 0.0, 0.0
    tau_a = s["acceleration_feedforward"] if default and s["feedforward"] else 0.0
    observer = (_ObserverReference(g, s["acceleration_feedforward"], s["speed_observer"], h)
                if default and s.get("speed_observer", 0.0) > 0.0 else None)
    voltage, last_reference = 0.0, None
    out = []
    for v_ref, v_meas in inputs:
        if observer is not None:
            v_meas = observer.update(v_meas, voltage)
            tracked = model_speed if tau_a else v_ref
        else:
            tracked = model_window if tau_a else v_ref
        error = tracked - v_meas
        rate = 0.0 if previous is None else (tau * rate + error - previous) / (tau + h)
        previous = error
        e_n, de_n = error / e_scale, rate / de_scale
        if s["mode"] == "fgs_pd":
            kp_n, kd_n = scheduler.evaluate_normalised(e_n, de_n)
            kp = s["kp_min"] + (s["kp_max"] - s["kp_min"]) * kp_n
            kd = s["kd_min"] + (s["kd_max"] - s["kd_min"]) * kd_n
        elif s["mode"] == "pd":
            kp, kd = s["pd_kp"], s["pd_kd"]
        else:
            kp, kd = s["pid_kp"], s["pid_kd"]
        if default:
            offset = g * v_ref if s["feedforward"] else 0.0
            if tau_a:
                a = math.exp(-h / tau_a)
                drive = min(max(v_ref + a / (1 - a) * (v_ref - model_speed), -limit / g),
                            limit / g)
                c = tau_a * (1 - a) / h
                model_window = c * model_speed + (1 - c) * drive
                model_speed = a * model_speed + (1 - a) * drive
                offset = g * drive
            if observer is not None and not (s["zero_reference_reset"] and v_ref == 0.0):
                if s["zero_reference_reset"] and last_reference == 0.0:
                    observer.state[2] = 0.0
                offset -= g * observer.state[2]
            proportional = g * s["gain_scale"] * (kp * error + kd * s["derivative_time"] * rate)
            increment = error * h
        else:
            offset = g * v_ref if s["feedforward"] else 0.0
            proportional = g * s["e_range"] * (kp * e_n + kd * de_n)
            increment = e_n * h
        if default and s["zero_reference_reset"] and v_ref == 0.0:
            integral = 0.0
        elif ki > 0.0:
            bound = s["v_supply"] / per_integral
            candidate = min(max(integral + increment, -bound), bound)
            raw = offset + proportional + per_integral * candidate
            if not ((raw > limit and error > 0.0) or (raw < -limit and error < 0.0)):
                integral = candidate
        raw = offset + proportional + per_integral * integral
        voltage = min(max(raw, -limit), limit)
        last_reference = v_ref
        out.append((voltage, kp, kd, e_n, de_n))
    return out


class _ObserverReference:
    """The default form's speed observer, recomputed: the wheel ``dx = u``,
    ``tau du = (V / g + d - u) dt``, ``dd = 0`` sampled by a matrix exponential, the current
    estimator's gains by Ackermann's formula for a triple pole at ``exp(-rate h)`` with numpy
    (not the closed forms and hand-written 3 x 3 algebra of the controller's own)."""

    def __init__(self, g, tau, rate, h):
        from scipy.linalg import expm

        continuous = np.zeros((4, 4))
        continuous[0, 1] = 1.0
        continuous[1, 1], continuous[1, 2], continuous[1, 3] = -1 / tau, 1 / tau, 1 / tau
        sampled = expm(continuous * h)
        self.a, self.b = sampled[:3, :3], sampled[:3, 3]
        c = np.array([1.0, 0.0, 0.0])
        observability = np.array([c @ np.linalg.matrix_power(self.a, k) for k in (1, 2, 3)])
        pole = math.exp(-rate * h)
        phi = np.linalg.matrix_power(self.a - pole * np.eye(3), 3)
        self.gains = phi @ np.linalg.solve(observability, [0.0, 0.0, 1.0])
        self.g = g
        self.state = np.zeros(3)
        self.position = 0.0
        self.h = h

    def update(self, v_meas, voltage):
        predicted = self.a @ self.state + self.b * (voltage / self.g)
        self.position += v_meas * self.h
        self.state = predicted + self.gains * (self.position - predicted[0])
        return float(self.state[1])


def _controller_inputs(settings, samples, seed):
    """Random (v_ref, v_meas): half the steps small moves (inside the universe), half jumps;
    the reference held over blocks of five samples (so the default form's reference model
    settles on it), every fourth block at exactly 0."""
    rng = np.random.default_rng(seed)
    default = settings.get("form", "default") == "default" and settings["mode"] != "pid"
    e_range = settings["fuzzy_e_range"] if default else settings["e_range"]
    inputs, error, v_ref = [], 0.0, 0.0
    for k in range(samples):
        if k % 5 == 0:
            v_ref = 0.0 if (k // 5) % 4 == 3 else float(rng.uniform(-0.4, 0.4))
        if (k // 10) % 2 == 0:
            error = float(np.clip(error + rng.normal(0.0, 0.025 * e_range), -0.8 * e_range,
                                  0.8 * e_range))
        else:
            error = float(rng.uniform(-2.5 * e_range, 2.5 * e_range))
        inputs.append((v_ref, v_ref - error))
    return inputs


def controller_fmu_comparison(settings, modes=("fgs_pd", "pd", "pid"), samples=60, seed=14,
                              h=0.02, fmu_dir=None, fmu_overrides=None):
    """Step the built WheelController FMU with random inputs; compare with the law.

    Parameters
    ----------
    settings : dict
        Controller parameters given to the FMU and to the reference.
    modes : sequence of str
        Each mode is one run.
    samples, seed : int
        Steps per run and the seed of the inputs.
    h : float
        Communication step [s].
    fmu_overrides : dict, optional
        Parameters given to the FMU only (a deliberately different controller, for the tests).

    Returns
    -------
    dict
        Per mode: largest |voltage difference| [V], largest kp/kd difference, and how many
        samples had ``|e_n| > 1`` or ``|de_n| > 1`` (outside the fuzzy universe).
    """
    from orchestrator.fmu.handle import FmuInstance

    inputs = _controller_inputs(settings, samples, seed)
    runs = {}
    with tempfile.TemporaryDirectory(prefix="sonotrack_verify_") as scratch:
        path = built_fmu("WheelController", fmu_dir or scratch)
        for mode in modes:
            law = dict(settings, mode=mode)
            reference = controller_law_reference(law, inputs, h)
            instance = FmuInstance(path, f"verify_controller_{mode}")
            names = set(instance.variables)
            values = {k: v for k, v in law.items() if k in names}
            values.update(fmu_overrides or {})
            instance.instantiate(0.0, samples * h, parameters=values)
            rows = []
            try:
                for k, (v_ref, v_meas) in enumerate(inputs):
                    instance.set_values({"v_ref": v_ref, "v_meas": v_meas})
                    instance.do_step(k * h, h)
                    rows.append(instance.get_values(["voltage", "kp", "kd"]))
            except Exception as exc:
                raise SimulationError(f"WheelController FMU ({mode}) failed: {exc}; FMU log: "
                                      f"{instance.last_error()}") from exc
            finally:
                instance.terminate()
            volts = np.array([r["voltage"] for r in rows])
            ref = np.array(reference)
            runs[mode] = {
                "max_voltage_difference_v": float(np.max(np.abs(volts - ref[:, 0]))),
                "max_gain_difference": float(max(
                    np.max(np.abs(np.array([r["kp"] for r in rows]) - ref[:, 1])),
                    np.max(np.abs(np.array([r["kd"] for r in rows]) - ref[:, 2])))),
                "outside_universe": int(np.sum((np.abs(ref[:, 3]) > 1) | (np.abs(ref[:, 4]) > 1))),
                "saturated": int(np.sum(np.abs(ref[:, 0]) >= settings["v_supply"])),
                "samples": samples,
            }
    return {"seed": seed, "step_s": h, "fmu_overrides": dict(fmu_overrides or {}), "runs": runs}


# ----- the closed loop through both FMUs ------------------------------------------------------
def closed_loop_fmu_comparison(model, settings, gain_points, step=0.1, duration=1.5,
                               encoder_ppr=1_000_000, fmu_dir=None, fmu_overrides=None,
                               ramp=None):
    """RobotPlant + two WheelControllers (fixed-PD or PID mode) in our master vs the TF.

    The master (Gauss-Seidel, controllers first, base step = the loop's period) runs one step
    at zero reference, then a reference step of ``step`` on both wheels (or, with ``ramp``,
    a ramp at ``ramp`` m/s^2 up to ``step``: what the planner gives). The plant's encoder
    resolution is raised to ``encoder_ppr`` (the linear model has no quantisation); every
    other parameter is RobotPlant's default, as in the model.

    Parameters
    ----------
    model : WheelLoopModel
        Gives the period and the closed-loop TF; must have ``extra_delay = 0``.
    settings : dict
        Controller parameters.
    gain_points : sequence of (mode, kp, kd, ki)
        ``mode`` "pd" (kp, kd in the form's units, ``ki`` its integral: ``trim_ki`` in the
        paper form, ``integral_gain`` in the default form) or "pid".
    fmu_overrides : dict, optional
        Controller parameters given to the FMUs only (tests).

    Returns
    -------
    dict
        Per gain point: largest |rim - step * TF| over both wheels [m/s] and as a fraction
        of the step, the traces (times, TF, left rim).
    """
    from orchestrator.fmu.handle import FmuInstance
    from orchestrator.run.master import InstanceSpec, Link, Master

    from .analysis import filter_through

    T = model.period
    steps = int(round(duration / T))
    plant = model.plant
    plant_values = {f.name: getattr(plant, f.name) for f in fields(plant)}
    plant_values["encoder_ppr"] = int(encoder_ppr)
    results = []
    with tempfile.TemporaryDirectory(prefix="sonotrack_verify_") as scratch:
        folder = fmu_dir or scratch
        plant_path = built_fmu("RobotPlant", folder)
        controller_path = built_fmu("WheelController", folder)
        for index, (mode, kp, kd, ki) in enumerate(gain_points):
            if mode == "pid":
                law = dict(settings, mode="pid", pid_kp=kp, pid_kd=kd, pid_ki=ki)
                loop, tf_gains = loop_model(model, law), (kp, kd, ki)
            else:
                integral = "integral_gain" if is_default_form(settings) else "trim_ki"
                law = dict(settings, mode="pd", pd_kp=kp, pd_kd=kd, **{integral: ki})
                loop, tf_gains = loop_model(model, law), loop_gains(law, kp, kd)
            plant_fmu = FmuInstance(plant_path, f"verify_loop_plant_{index}")
            plant_params = {k: v for k, v in plant_values.items() if k in plant_fmu.variables}
            controllers = {}
            for side in ("left", "right"):
                handle = FmuInstance(controller_path, f"verify_loop_{side}_{index}")
                values = {k: v for k, v in law.items() if k in handle.variables}
                values.update(fmu_overrides or {})
                controllers[side] = InstanceSpec(side, handle, parameters=values)
            # Gauss-Seidel order: the controllers read the plant's sample at t_k, then the
            # plant integrates [t_k, t_k + T] with their voltages (the model's delay 0).
            specs = [controllers["left"], controllers["right"],
                     InstanceSpec("plant", plant_fmu, parameters=plant_params)]
            links = [Link(f"{side}.voltage", f"plant.voltage_{side}") for side in
                     ("left", "right")]
            links += [Link(f"plant.wheel_speed_{side}", f"{side}.v_meas") for side in
                      ("left", "right")]
            master = Master(specs, links, T)
            master.initialize(0.0, (steps + 1) * T)
            group = master.output_group("plant", "Real", ["rim_speed_left", "rim_speed_right"])
            rims = []
            # the reference applied from master step k = 1 on (a step, or a ramp at `ramp`)
            reference = [step if ramp is None else min(step, ramp * k * T)
                         for k in range(1, steps + 2)]
            try:
                master.step(0)
                rims.append(list(master.read_outputs("plant", group)))
                for k in range(1, steps + 1):
                    for spec in controllers.values():
                        spec.handle.set_values({"v_ref": reference[k - 1]})
                    master.step(k)
                    rims.append(list(master.read_outputs("plant", group)))
            finally:
                master.terminate()
            rims = np.array(rims)
            times = np.arange(steps + 1) * T
            tf = filter_through(loop.closed_loop_tf(*tf_gains, "rim"), reference)
            difference = float(np.max(np.abs(rims - tf[:, None])))
            results.append({"mode": mode, "kp": float(kp), "kd": float(kd), "ki": float(ki),
                            "max_abs_difference_m_s": difference,
                            "max_difference_fraction_of_step": difference / step,
                            "times": times.tolist(), "tf_rim_speed": tf.tolist(),
                            "fmu_rim_speed_left": rims[:, 0].tolist()})
    return {"step_m_s": float(step), "period_s": float(T), "encoder_ppr": int(encoder_ppr),
            "ramp_m_s2": None if ramp is None else float(ramp),
            "fmu_overrides": dict(fmu_overrides or {}), "points": results}

"""Paper Case 1 on the nonlinear RobotPlant core: FGS-PD against the paper's CPID.

Case 1 (Table 6): a static target 2 m away at 45 deg; the left wheel ramps to 0.342 m/s at
0.342 m/s^2, the right to 0.258 m/s at 0.258 m/s^2 (same ramp time, 1 s), both cruise for
the same time and ramp down. Each wheel's controller runs at the encoder speed window
(20 ms): a faster loop would only see the same held count difference again. Unlike the
linear analyses this run has everything the plant core has: the encoder's 728 counts per
revolution, voltage saturation, slip, the scheduling itself.

Metrics on the true rim speed during ramp-up and cruise (python-control ``step_info`` on the
recorded trace, ``yfinal`` = cruise speed): overshoot [%], settling time into a +-5 % band
[s] (the encoder's quantum, 26 mm/s at 20 ms, makes the loop dither by about +-1.5 % at
0.342 m/s and +-3 % at 0.258 m/s, so a 2 % band is never entered for good), and the RMS of
v_ref - v over the whole run [mm/s]. ``sonotrack verify`` judges the paper's overshoot claim
on it (check ``fgs_pd_overshoot_vs_pid``); ``benchmarks/wheel_loop.py`` prints the table of
docs/control.md.
"""

import control
import numpy as np

from components.control import WheelSpeedController
from components.plant import RobotPlantCore

__all__ = ["CASE1", "CONFIGS", "SETTLING_BAND", "trapezoid", "run_case1", "wheel_metrics",
           "compare"]

CASE1 = {"left": (0.342, 0.342, 2.528), "right": (0.258, 0.258, 1.9)}  # v, a, distance
CONFIGS = {
    "fgs_pd": {"mode": "fgs_pd"},                                      # the default form
    "fgs_pd_mamdani": {"mode": "fgs_pd", "fuzzy_method": "mamdani"},
    "pd": {"mode": "pd"},
    "fgs_pd_paper": {"mode": "fgs_pd", "form": "paper"},
    "fgs_pd_paper_mamdani": {"mode": "fgs_pd", "form": "paper", "fuzzy_method": "mamdani"},
    "fgs_pd_pure": {"mode": "fgs_pd", "form": "paper", "trim_ki": 0.0},  # Eq. (46) alone
    "pid": {"mode": "pid"},
    "pid_no_feedforward": {"mode": "pid", "feedforward": False},
}
SETTLING_BAND = 0.05


def trapezoid(t, v, a, cruise_time):
    """Speed of a trapezoidal profile: ramp at ``a`` to ``v``, cruise, ramp down to 0."""
    ramp = v / a
    if t < ramp:
        return a * t
    if t < ramp + cruise_time:
        return v
    if t < 2 * ramp + cruise_time:
        return v - a * (t - ramp - cruise_time)
    return 0.0


def run_case1(controller_parameters, h=0.02, tail=1.5, plant_parameters=None):
    """Run both wheels on Case 1 and return time, references and true rim speeds.

    Parameters
    ----------
    controller_parameters : dict
        Keyword arguments of :class:`WheelSpeedController` (the same for both wheels).
    plant_parameters : PlantParameters, optional
        RobotPlant's defaults when None.
    h : float
        Control and communication period [s].
    tail : float
        Time simulated after the ramp-down ends [s].

    Returns
    -------
    dict
        ``t``, ``ref_left``, ``ref_right``, ``v_left``, ``v_right`` (arrays) and
        ``cruise_end`` [s].
    """
    v_l, a_l, d_l = CASE1["left"]
    cruise_time = d_l / v_l - v_l / a_l  # both wheels share ramp and cruise times
    ramp = v_l / a_l
    plant = RobotPlantCore(plant_parameters)
    left = WheelSpeedController(**controller_parameters)
    right = WheelSpeedController(**controller_parameters)
    n = int(round((2 * ramp + cruise_time + tail) / h))
    rec = np.zeros((n + 1, 5))
    for k in range(n):
        t = k * h
        ref_l = trapezoid(t, *CASE1["left"][:2], cruise_time)
        ref_r = trapezoid(t, *CASE1["right"][:2], cruise_time)
        u_l = left.step(ref_l, plant.wheel_speed_left, h)
        u_r = right.step(ref_r, plant.wheel_speed_right, h)
        plant.step(u_l, u_r, h)
        t1 = (k + 1) * h
        rec[k + 1] = (t1, trapezoid(t1, *CASE1["left"][:2], cruise_time),
                      trapezoid(t1, *CASE1["right"][:2], cruise_time),
                      plant.rim_speed_left, plant.rim_speed_right)
    return {"t": rec[:, 0], "ref_left": rec[:, 1], "ref_right": rec[:, 2],
            "v_left": rec[:, 3], "v_right": rec[:, 4], "cruise_end": ramp + cruise_time}


def wheel_metrics(t, ref, v, cruise_speed, cruise_end):
    """Overshoot [%], settling time [s] (step_info, +-5 % band), RMS error [m/s], dither [m/s].

    ``dither`` is the peak-to-peak true speed over the last second of cruise.
    """
    upto = t <= cruise_end + 1e-9
    info = control.step_info(v[upto], T=t[upto], yfinal=cruise_speed,
                             SettlingTimeThreshold=SETTLING_BAND)
    last = (t > cruise_end - 1.0) & upto
    return {
        "overshoot_percent": _finite_or_none(info["Overshoot"]),
        "settling_time_s": _finite_or_none(info["SettlingTime"]),
        "rms_error_m_s": float(np.sqrt(np.mean((ref - v) ** 2))),
        "mean_cruise_error_m_s": float(np.mean(ref[last] - v[last])),
        "dither_pp_m_s": float(np.ptp(v[last])),
    }


def _finite_or_none(value):
    # step_info gives NaN when the trace never settles; JSON has no NaN.
    value = float(value)
    return value if np.isfinite(value) else None


def compare(configs=CONFIGS, h=0.02, plant_parameters=None):
    """Run every configuration on Case 1 and return metrics per configuration and wheel.

    Parameters
    ----------
    configs : dict
        Name -> keyword arguments of :class:`WheelSpeedController`.
    h : float
        Control period [s].
    plant_parameters : PlantParameters, optional

    Returns
    -------
    dict
        Name -> ``left`` / ``right`` -> :func:`wheel_metrics`.
    """
    results = {}
    for name, parameters in configs.items():
        trace = run_case1(parameters, h=h, plant_parameters=plant_parameters)
        results[name] = {
            side: wheel_metrics(trace["t"], trace[f"ref_{side}"], trace[f"v_{side}"],
                                CASE1[side][0], trace["cruise_end"])
            for side in ("left", "right")}
    return results

"""The wheel-speed loop's figures per design: the default form, the paper's form, the CPID.

Per design (the same experiments ``sonotrack verify`` judges, :mod:`orchestrator.verify`):
2 % settling of a 0.3 m/s step on wheels with x0.25 / x1 / x4 RobotPlant's DC gain, recovery
from a load-torque step of 20 % of stall, creep after a stop, each on the discrete-time loop;
overshoot on paper Case 1's ramp (RobotPlant core, :mod:`orchestrator.verify.case1`); the 5-95 %
spread of the scheduled kp and kd in paper Cases 1 and 2 (``scenarios/static_case1.toml``,
``scenarios/dynamic_case2.toml``, the whole system through the FMUs). Then the measurement
behind the requirements' judged range (``family``: the best any PD/PID with feedforward can do
over the issue's whole grid, and the two corners that pull the gains apart), the physical
bound on settling at every wheel of that grid (``settling_bound``: the fastest any controller
can settle with the supply voltage, beside the default form as shipped and the default form
given the wheel's own two constants), the mechanism of slip chatter at low friction
(``slip_chatter``: slide entries with the real encoder, with a 10^6-count one, and with the
planner's ramp at half of mu g), the trade-off behind ``scenarios/faults/encoder_skip.toml``
(``encoder_skip``: the body's peak speed there against load-step recovery, over the default
form's gains), and the four shipped scenarios' summary figures in both forms (``scenarios``).

Run: ``.venv/bin/python benchmarks/wheel_loop.py`` (``--quick`` for a short check: one
scenario, a small family search) -> ``benchmarks/results/wheel_loop.json``.
"""

import argparse
import itertools
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from components.control import DEFAULTS  # noqa: E402
from components.plant import PlantParameters  # noqa: E402
from orchestrator.verify.case1 import (  # noqa: E402,F401  (re-exported for the tests)
    CASE1, CONFIGS, SETTLING_BAND, compare, run_case1, trapezoid, wheel_metrics,
)
from orchestrator.verify.checks import load_requirements  # noqa: E402
from orchestrator.verify.designs import DESIGNS, design_settings  # noqa: E402
from orchestrator.verify.requirement_runs import run_model_experiment  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "wheel_loop.json"
# The default form as it was before its speed observer: the encoder's window speed, the
# integral of the error at 22 1/s, the fuzzy universe at one encoder count per window
BEFORE_OBSERVER = {"speed_observer": 0.0, "integral_gain": 22.0, "fuzzy_e_range": 0.0259,
                   "fuzzy_de_range": 0.432}
SCENARIOS = ("s_curve", "straight", "static_case1", "dynamic_case2")


def _commissioned(settings, plant, cell, req):
    """``settings`` commissioned on the sampled wheel of ``cell`` (as verify judges)."""
    from orchestrator.verify.commissioning import commission_model, commissioned

    return commissioned(settings, commission_model(plant, cell, req["commissioning"]))


def loop_figures(req):
    """Settling at x0.25 / x1 / x4 gain, load recovery and creep, per design (tau x1), each
    design commissioned on each wheel; the default form also as shipped (RobotPlant's
    constants on every wheel)."""
    grid, plant = req["off_nominal_grid"], PlantParameters()
    out = {}
    for name, form, commission in (*((d, d, True) for d in DESIGNS),
                                   ("default_uncommissioned", "default", False)):
        settings = design_settings(dict(DEFAULTS), form)

        def run(requirement, cell):
            own = _commissioned(settings, plant, cell, req) if commission else settings
            return run_model_experiment(requirement, own, plant, cell, req, grid)
        creep = run("no_creep", (1.0, 1.0))
        out[name] = {
            "settling_s": {f"x{g:g}": _finite(run("off_nominal_settling", (g, 1.0))["value"])
                           for g in (0.25, 1.0, 4.0)},
            "load_recovery_s": _finite(run("load_step_recovery", (1.0, 1.0))["value"]),
            "creep_m": creep["value"], "stop_overrun_m": creep["overrun_m"],
            "creep_at_half_gain_m": run("no_creep", (0.5, 1.0))["value"],
        }
    return out


def case1_overshoot():
    """Overshoot [%] of the true rim speed on paper Case 1's ramp, left / right, per design."""
    configs = {name: design_settings(dict(DEFAULTS), name) for name in DESIGNS}
    results = compare(configs)
    return {name: {side: results[name][side]["overshoot_percent"] for side in ("left", "right")}
            for name in results}


def _finite(value):
    return value if value is not None and math.isfinite(value) else None


def _scenario_run(name, parameters, fmu_dir, out, outputs=None):
    from orchestrator.run import run_scenario
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / f"{name}.toml")
    changes = {"parameters": parameters}
    if outputs:
        changes["outputs"] = list(dict.fromkeys(scenario.outputs + outputs))
    result = run_scenario(scenario.with_overrides(**changes), out, progress=False,
                          fmu_dir=fmu_dir, plots=False)
    return result


def _both(design):
    return {f"controller_{side}.{key}": value for side in ("left", "right")
            for key, value in DESIGNS[design].items()}


def gain_spread(fmu_dir, scratch):
    """5-95 % of the scheduled kp and kd over both wheels in paper Cases 1 and 2."""
    import csv

    gains = [f"controller_{side}.{g}" for side in ("left", "right") for g in ("kp", "kd")]
    out = {}
    for case in ("static_case1", "dynamic_case2"):
        out[case] = {}
        for design in DESIGNS:
            result = _scenario_run(case, _both(design), fmu_dir, scratch / f"{case}_{design}",
                                   outputs=gains)
            with open(result.results_csv, newline="") as handle:
                rows = list(csv.DictReader(handle))
            spread = {}
            for gain in ("kp", "kd"):
                values = np.array([float(r[f"controller_{side}.{gain}"]) for r in rows
                                   for side in ("left", "right")])
                spread[gain] = [float(np.percentile(values, 5)), float(np.percentile(values, 95))]
            out[case][design] = spread
    return out


def scenario_summaries(fmu_dir, scratch, names):
    """Final distance to the source and path RMSE of the shipped scenarios, per FGS-PD form."""
    out = {}
    for name in names:
        out[name] = {}
        for design in ("default", "paper"):
            summary = _scenario_run(name, _both(design), fmu_dir,
                                    scratch / f"summary_{name}_{design}").summary
            out[name][design] = {key: summary.get(key) for key in
                                 ("final_distance_to_source_m", "path_rmse_m",
                                  "final_position_error_m")}
    return out


def family(req, quick):
    """What the controller family the issue names can do over the issue's whole grid.

    ``linear``: on the sampled linear loop (frozen gains, feedforward), the best worst-case
    2 % settling time over gain x0.25..x4 by tau x0.2..x2 of any PID in the searched box.
    ``corners``: the default form's structure on the discrete-time loop with other gains:
    which fail settling on the slow weak corner (x0.5, x2) and which limit-cycle on the fast
    strong one (x2, x0.5).
    """
    from dataclasses import replace

    from orchestrator.verify.analysis import filter_through, step_figures
    from orchestrator.verify.loop_model import WheelLoopModel

    base = WheelLoopModel()
    times = np.arange(301) * base.period
    gains = [float(g) for g in req["off_nominal_grid"]["gain_factors"]]
    taus = [float(t) for t in req["off_nominal_grid"]["time_constant_factors"]]
    models = {(g, t): replace(base, gain_factor=g, time_constant_factor=t)
              for g in gains for t in taus}

    def worst(kp, kd, ki):
        value = 0.0
        for model in models.values():
            if np.max(np.abs(np.roots(model.characteristic_polynomial(kp, kd, ki)))) >= 1.0:
                return math.inf
            y = filter_through(model.closed_loop_tf(kp, kd, ki, "rim"), np.ones(times.size))
            value = max(value, step_figures(y, times, 1.0, 0.02)[2])
        return value

    kps = (0.5, 1.0, 1.5, 2.0, 3.0) if quick else (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)
    kds = (0.0, 0.3) if quick else (0.0, 0.3, 1.0)
    kis = (4, 6, 12) if quick else (2, 4, 6, 8, 12, 16, 25, 40)
    searched = [(worst(kp, kd, ki), kp, kd, ki) for kp, kd, ki in itertools.product(kps, kds, kis)]
    best = min(searched)
    linear = {"searched": len(searched), "kp": list(kps), "kd": list(kds), "ki": list(kis),
              "best_worst_settling_s": best[0], "at": {"kp": best[1], "kd": best[2],
                                                       "ki": best[3]}}
    plant, grid = PlantParameters(), req["off_nominal_grid"]
    scales = (0.9, 1.2, 1.5) if quick else (0.6, 0.9, 1.05, 1.2, 1.35, 1.5, 1.7)
    integrals = (16, 28) if quick else (8, 12, 16, 22, 28, 36)
    rows = []
    for scale, integral in itertools.product(scales, integrals):
        settings = dict(DEFAULTS, gain_scale=scale, integral_gain=integral)
        weak = run_model_experiment("off_nominal_settling", settings, plant, (0.5, 2.0), req, grid)
        strong = run_model_experiment("no_limit_cycle", settings, plant, (2.0, 0.5), req, grid)
        rows.append({"gain_scale": scale, "integral_gain": integral,
                     "settling_weak_slow_s": _finite(weak["value"]),
                     "limit_cycle_strong_fast_quanta": _finite(strong["value"]),
                     "both_hold": weak["passed"] and strong["passed"]})
    corners = {"designs": rows, "both_hold": sum(r["both_hold"] for r in rows)}
    return {"linear": linear, "corners": corners}


# (gain_scale, integral_gain) of the default form: the shipped set first, then softer and
# stiffer ones; the encoder_skip trade-off is measured over these.
SKIP_GAINS = ((1.2, 22.0), (1.2, 40.0), (0.9, 16.0), (1.2, 8.0), (0.6, 8.0), (0.3, 6.0),
              (1.2, 0.0))


def encoder_skip_tradeoff(req, fmu_dir, scratch, quick=False):
    """Peak body speed in ``faults/encoder_skip`` (bound 1.05 v_max = 0.42 m/s) against the
    worst load-step recovery on the judged wheels (each commissioned), for the shipped default
    form and for the default form's gain sets before its speed observer (the integral of the
    error instead); the paper form's peak beside it. A half-counting encoder reads as a wheel
    at half speed, which the loop answers as it answers a load, until the planner's odometry
    check stops the robot."""
    import numpy as np

    from orchestrator.run.results import read_results
    from orchestrator.verify.wheel_experiments import judged_cells

    plant, grid = PlantParameters(), req["off_nominal_grid"]

    def peak(parameters, tag):
        both = {f"controller_{side}.{k}": v for side in ("left", "right")
                for k, v in parameters.items()}
        result = _scenario_run("faults/encoder_skip", both, fmu_dir, scratch / f"skip_{tag}")
        return float(np.max(np.abs(read_results(result.results_csv)["plant.speed"])))

    def worst_recovery(settings):
        return max(run_model_experiment("load_step_recovery",
                                        _commissioned(settings, plant, cell, req), plant, cell,
                                        req, grid)["value"] for cell in judged_cells(grid))

    sets = [{}] + [dict(BEFORE_OBSERVER, gain_scale=scale, integral_gain=integral)
                   for scale, integral in (SKIP_GAINS[:2] if quick else SKIP_GAINS)]
    rows = []
    for changes in sets:
        settings = dict(DEFAULTS, **changes)
        rows.append({"shipped": not changes,
                     "speed_observer": settings["speed_observer"],
                     "gain_scale": settings["gain_scale"],
                     "integral_gain": settings["integral_gain"],
                     "peak_body_speed_m_s": peak(changes, "_".join(
                         f"{v:g}" for v in changes.values()) or "shipped"),
                     "worst_load_recovery_s": _finite(worst_recovery(settings))})
    for row in rows:
        row["meets_both"] = (row["peak_body_speed_m_s"] <= 0.42 and row["worst_load_recovery_s"]
                             is not None and row["worst_load_recovery_s"] <= 1.0)
    return {"default_form": rows, "paper_form_peak_m_s": peak({"form": "paper"}, "paper"),
            "bound_m_s": 0.42, "meets_both": sum(r["meets_both"] for r in rows)}


def slip_chatter_mechanism(req):
    """Most slide entries in 1 s (requirement: <= 2) per judged wheel and friction 0.05 / 0.1,
    on the RobotPlant core: the shipped default form commissioned on each wheel; and the
    default form before its speed observer (the encoder's window speed, the integral of the
    error; RobotPlant's constants, as judged until then) with the real encoder, with a
    10^6-count one (the speed quantum 19 um/s instead of 25.9 mm/s), and with the ramp at
    mu g / 2 = 0.245 m/s^2: the mechanism the observer removes."""
    from dataclasses import replace

    from orchestrator.verify.requirement_runs import no_slip_chatter
    from orchestrator.verify.wheel_experiments import judged_cells

    plant, grid = PlantParameters(), req["off_nominal_grid"]
    table = req["no_slip_chatter"]
    before = dict(DEFAULTS, **BEFORE_OBSERVER)
    frictions = dict(grid, frictions=[0.05, 0.1])
    cases = {"before_observer": (plant, table),
             "before_observer_fine_encoder": (replace(plant, encoder_ppr=1_000_000), table),
             "before_observer_ramp_half_mu_g": (plant, dict(table, acceleration_m_s2=0.245))}
    rows = []
    for cell in judged_cells(grid):
        row = {"gain_factor": cell[0], "time_constant_factor": cell[1],
               "shipped_commissioned": no_slip_chatter(
                   _commissioned(dict(DEFAULTS), plant, cell, req), plant, cell, table,
                   frictions)["per_friction"]}
        for name, (base, ramp) in cases.items():
            row[name] = no_slip_chatter(before, base, cell, ramp, frictions)["per_friction"]
        rows.append(row)
    names = ("shipped_commissioned", *cases)
    return {"rows": rows,
            "worst": {name: max(max(r[name].values()) for r in rows) for name in names}}


def settling_bound(req):
    """Per grid wheel: the minimum 2 % settling time of any controller (saturated supply,
    :mod:`orchestrator.verify.settling_bound`), continuous and on the 20 ms samples; the
    default form's settling as shipped and with ``volts_per_speed`` and
    ``acceleration_feedforward`` set to that wheel's own DC gain and time constant."""
    from orchestrator.verify.loop_model import linear_wheel_model
    from orchestrator.verify.settling_bound import minimum_settling_time

    plant, grid = PlantParameters(), req["off_nominal_grid"]
    table = req["off_nominal_settling"]
    speed, band = table["step_m_s"], table["band_fraction"]
    rows = []
    for g in grid["gain_factors"]:
        for t in grid["time_constant_factors"]:
            cell = (float(g), float(t))
            model = linear_wheel_model(plant).scaled(*cell)
            own = dict(DEFAULTS, volts_per_speed=1.0 / model.dc_gain,
                       acceleration_feedforward=model.time_constants[1])
            rows.append({
                "gain_factor": cell[0], "time_constant_factor": cell[1],
                "minimum_s": minimum_settling_time(model, speed, band, plant.v_supply),
                "minimum_sampled_s": minimum_settling_time(model, speed, band, plant.v_supply,
                                                           plant.speed_window),
                "default_form_s": _finite(run_model_experiment(
                    "off_nominal_settling", dict(DEFAULTS), plant, cell, req, grid)["value"]),
                "default_form_own_constants_s": _finite(run_model_experiment(
                    "off_nominal_settling", own, plant, cell, req, grid)["value"])})
    return {"rows": rows, "largest_minimum_s": max(r["minimum_sampled_s"] for r in rows),
            "target_s": table["max_settling_time_s"]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="one scenario and a small family search (a check that it runs)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    load_before = os.getloadavg()
    req = load_requirements()
    out = {"designs": {name: DESIGNS[name] for name in DESIGNS}, "control_period_s": 0.02,
           "commissioning": dict(req["commissioning"], why=None)}
    out["loop"] = loop_figures(req)
    out["case1_overshoot_percent"] = case1_overshoot()
    with tempfile.TemporaryDirectory(prefix="wheel_loop_") as scratch:
        scratch = Path(scratch)
        from orchestrator.builder.fmus import build_all

        build_all(scratch / "fmus")
        out["gain_spread_5_95"] = gain_spread(scratch / "fmus", scratch)
        out["encoder_skip"] = encoder_skip_tradeoff(req, scratch / "fmus", scratch, args.quick)
        out["scenarios"] = scenario_summaries(scratch / "fmus", scratch,
                                              SCENARIOS[:1] if args.quick else SCENARIOS)
    out["family"] = family(req, args.quick)
    out["settling_bound"] = settling_bound(req)
    out["slip_chatter"] = slip_chatter_mechanism(req)
    out["quick"] = bool(args.quick)
    out["wall_time_s"] = time.perf_counter() - started
    # 1-, 5- and 15-minute load averages: the wall time depends on them (the figures do not)
    out["load_average"] = {"before": list(load_before), "after": list(os.getloadavg())}
    _print(out)
    RESULTS.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {RESULTS} ({out['wall_time_s']:.1f} s)")


def _print(out):
    def s(value, spec=".2f"):
        return "never" if value is None else format(value, spec)
    print(f"{'design':22s} {'settle x0.25':>12s} {'x1':>6s} {'x4':>6s} {'load s':>7s} "
          f"{'creep mm':>9s} {'Case 1 overshoot %':>19s}")
    for name, f in out["loop"].items():
        st = f["settling_s"]
        over = out["case1_overshoot_percent"].get(name)
        print(f"{name:22s} {s(st['x0.25']):>12s} {s(st['x1']):>6s} {s(st['x4']):>6s} "
              f"{s(f['load_recovery_s']):>7s} {1000 * f['creep_m']:9.3f} "
              + (f"{s(over['left'])} / {s(over['right'])}" if over else ""))
    for case, designs in out["gain_spread_5_95"].items():
        for name, spread in designs.items():
            print(f"{case:14s} {name:8s} kp 5-95 % {spread['kp'][0]:.2f}..{spread['kp'][1]:.2f}"
                  f"  kd {spread['kd'][0]:.2f}..{spread['kd'][1]:.2f}")
    for name, forms in out["scenarios"].items():
        print(f"{name:14s} " + "  ".join(
            f"{form}: final {f['final_distance_to_source_m']:.3f} m, RMSE "
            f"{f['path_rmse_m']:.3f} m" for form, f in forms.items()))
    lin, corners = out["family"]["linear"], out["family"]["corners"]
    print(f"family: best worst-case 2 % settling over the whole grid "
          f"{s(lin['best_worst_settling_s'])} s (of {lin['searched']} PID gain sets); "
          f"{corners['both_hold']} of "
          f"{len(corners['designs'])} default-form gain sets meet both corners")
    for row in out["slip_chatter"]["rows"]:
        def pair(name):
            return f"{row[name]['0.05']} / {row[name]['0.1']}"
        print(f"slip chatter gain x{row['gain_factor']:g} tau x{row['time_constant_factor']:g}"
              f" (mu 0.05 / 0.1): shipped, commissioned {pair('shipped_commissioned')}; before "
              f"the observer {pair('before_observer')}, 10^6 counts "
              f"{pair('before_observer_fine_encoder')}, ramp mu g/2 "
              f"{pair('before_observer_ramp_half_mu_g')}")
    skip = out["encoder_skip"]
    for row in skip["default_form"]:
        print(f"encoder_skip: {'shipped' if row['shipped'] else 'before the observer'}, "
              f"observer {row['speed_observer']:g} rad/s, gain_scale {row['gain_scale']:g}, "
              f"integral_gain {row['integral_gain']:g}: peak body "
              f"{row['peak_body_speed_m_s']:.3f} m/s, "
              f"worst load recovery {s(row['worst_load_recovery_s'])}"
              f"{'' if row['worst_load_recovery_s'] is None else ' s'}")
    print(f"encoder_skip: paper form peak {skip['paper_form_peak_m_s']:.3f} m/s; "
          f"{skip['meets_both']} of these default-form sets meet both 0.42 m/s and 1 s")
    bound = out["settling_bound"]
    own = [r["default_form_own_constants_s"] for r in bound["rows"]]
    print(f"settling bound: any controller needs at most {bound['largest_minimum_s']:.2f} s "
          f"on the grid (target {bound['target_s']:g} s); the default form with each wheel's "
          f"own constants {s(min(own))}..{s(max(own))} s")


if __name__ == "__main__":
    main()

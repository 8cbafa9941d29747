"""Cost of one fuzzy inference: ours against scikit-fuzzy's ControlSystemSimulation.

Both run the same rule base (seven triangular sets on e and de, the Zhao-Tomizuka-Isaka
tables, Mamdani max-min, centroid over Small/Big) on the same random inputs in one process.
Ours is timed with ``centroid="exact"`` (closed form, the FMU's path for
``fuzzy_method="mamdani"``) and with the weighted-average default; scikit-fuzzy is timed per
scalar evaluation, as a controller would call it. ``max_abs_diff`` is the largest difference
of our exact centroid from scikit-fuzzy's (sampled) one; ``max_abs_diff_discrete`` that of our
sampled centroid on the same universe. Run: ``.venv/bin/python benchmarks/fuzzy_speed.py``.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from components.control import INPUT_TERMS, KD_TABLE, KP_TABLE, FuzzyGainScheduler  # noqa: E402

INPUT_POINTS = 601   # step 1/300: every set vertex k/3 is a sample, so sampling is exact
OUTPUT_POINTS = 101


def skfuzzy_system(input_points=INPUT_POINTS, output_points=OUTPUT_POINTS):
    """The rule base in ``skfuzzy.control``; returns a ControlSystem."""
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    universe_in = np.linspace(-1.0, 1.0, input_points)
    universe_out = np.linspace(0.0, 1.0, output_points)
    e = ctrl.Antecedent(universe_in, "e")
    de = ctrl.Antecedent(universe_in, "de")
    kp = ctrl.Consequent(universe_out, "kp", defuzzify_method="centroid")
    kd = ctrl.Consequent(universe_out, "kd", defuzzify_method="centroid")
    peaks = np.linspace(-1.0, 1.0, len(INPUT_TERMS))
    last = len(INPUT_TERMS) - 1
    for variable in (e, de):
        for k, term in enumerate(INPUT_TERMS):
            abc = [peaks[max(k - 1, 0)], peaks[k], peaks[min(k + 1, last)]]
            variable[term] = fuzz.trimf(universe_in, abc)
    for variable in (kp, kd):
        variable["S"] = fuzz.trimf(universe_out, [0.0, 0.0, 1.0])
        variable["B"] = fuzz.trimf(universe_out, [0.0, 1.0, 1.0])
    rules = [ctrl.Rule(e[a] & de[b], (kp[KP_TABLE[i][j]], kd[KD_TABLE[i][j]]))
             for i, a in enumerate(INPUT_TERMS) for j, b in enumerate(INPUT_TERMS)]
    return ctrl.ControlSystem(rules)


def main(n_ours=20000, n_skfuzzy=40, seed=0):
    from skfuzzy import control as ctrl

    rng = np.random.default_rng(seed)
    inputs = rng.uniform(-1.2, 1.2, size=(max(n_ours, n_skfuzzy), 2)).tolist()
    exact = FuzzyGainScheduler(1.0, 1.0, method="mamdani", centroid="exact")
    discrete = FuzzyGainScheduler(1.0, 1.0, method="mamdani", centroid="discrete",
                                  universe_points=OUTPUT_POINTS)
    weighted = FuzzyGainScheduler(1.0, 1.0, method="weighted")
    sim = ctrl.ControlSystemSimulation(skfuzzy_system(), cache=False)

    def ours(engine, n):
        evaluate = engine.evaluate_normalised
        start = time.perf_counter()
        for e, de in inputs[:n]:
            evaluate(e, de)
        return (time.perf_counter() - start) / n * 1e6

    our_us = min(ours(exact, n_ours) for _ in range(5))
    weighted_us = min(ours(weighted, n_ours) for _ in range(5))
    reference = []
    start = time.perf_counter()
    for e, de in inputs[:n_skfuzzy]:
        sim.input["e"] = e
        sim.input["de"] = de
        sim.compute()
        reference.append((sim.output["kp"], sim.output["kd"]))
    sk_us = (time.perf_counter() - start) / n_skfuzzy * 1e6
    reference = np.array(reference)
    ours_exact = np.array([exact.evaluate_normalised(e, de) for e, de in inputs[:n_skfuzzy]])
    ours_discrete = np.array([discrete.evaluate_normalised(e, de)
                              for e, de in inputs[:n_skfuzzy]])
    result = {
        "our_us_per_eval": our_us,
        "our_weighted_us_per_eval": weighted_us,
        "skfuzzy_us_per_eval": sk_us,
        "speedup": sk_us / our_us,
        "max_abs_diff": float(np.abs(ours_exact - reference).max()),
        "max_abs_diff_discrete": float(np.abs(ours_discrete - reference).max()),
        "n_ours": n_ours, "n_skfuzzy": n_skfuzzy,
        "output_universe_points": OUTPUT_POINTS, "input_universe_points": INPUT_POINTS,
        "python": sys.version.split()[0],
    }
    out = ROOT / "benchmarks" / "results" / "fuzzy_speed.json"
    out.write_text(json.dumps(result, indent=2) + "\n")
    for key, value in result.items():
        print(f"{key:28s} {value}")
    print(f"wrote {out}")
    return result


if __name__ == "__main__":
    main()

"""Range and bearing errors of the AcousticLocalizer from microphone offsets and ADC channel skew.

The array as built is not the array the estimator assumes (docs/acoustics.md, "The array's
imperfections"). For each imperfection alone, and for the issue's two cases, one noise-free fix
(24-bit ADC, 120 dB: the delays are exact to 2e-11 s) per distance and bearing gives the error
the imperfection causes; then ``--draws`` random arrays with every offset uniform in
``+-offset_band`` and both skews uniform in ``+-skew_band`` give the spread a Monte Carlo
study would see. Prints tables and writes ``benchmarks/results/array_imperfections.json``.

    .venv/bin/python benchmarks/array_imperfections.py [--draws 200] [--offset-band 1e-3]
        [--skew-band 6.7e-6]
"""

import argparse
import json
import math
import platform
import time
from pathlib import Path

import numpy as np

from components.acoustics import LocalizerCore
from components.acoustics.settings import IMPERFECTIONS

RESULTS = Path(__file__).resolve().parent / "results"
QUIET = dict(snr_db=120.0, adc_bits=24, seed=0)
DISTANCES_M = (1.0, 2.0, 3.0, 4.0)
BEARINGS_DEG = (0.0, 30.0, 60.0)
# One at a time, at the magnitudes (1 mm, 3.3 us), and the two cases.
CASES = {name: {name: 1e-3} for name in IMPERFECTIONS if name.startswith("mic_")}
CASES.update({name: {name: 3.3e-6} for name in IMPERFECTIONS if name.startswith("adc_")})
CASES.update({
    "centre 1 mm forward (issue)": {"mic_centre_across": 1e-3},
    "outer channels 3.3 us early (issue)": {"adc_skew_left": -3.3e-6, "adc_skew_right": -3.3e-6},
    "scan left, centre, right at 300 kS/s": {"adc_skew_left": -3.33e-6,
                                             "adc_skew_right": 3.33e-6},
})


def fix_error(distance, bearing_deg, parameters):
    """``(range error [m], bearing error [deg])`` of one noise-free fix, robot at the origin facing +y."""
    core = LocalizerCore(**QUIET, **parameters)
    bearing = math.radians(bearing_deg)
    core.step(0.0, 0.01, -distance * math.sin(bearing), distance * math.cos(bearing), True,
              0.0, 0.0, math.pi / 2)
    if not core.valid:
        return math.nan, math.nan
    return core.distance - distance, math.degrees(core.bearing - bearing)


def one_at_a_time():
    rows = []
    for case, parameters in CASES.items():
        for distance in DISTANCES_M:
            for bearing in BEARINGS_DEG:
                error_range, error_bearing = fix_error(distance, bearing, parameters)
                rows.append(dict(case=case, parameters=parameters, distance_m=distance,
                                 bearing_deg=bearing, range_error_m=error_range,
                                 bearing_error_deg=error_bearing))
    return rows


def random_arrays(draws, offset_band, skew_band, seed=2026):
    """Errors over random arrays: every offset in +-offset_band, both skews in +-skew_band."""
    rng = np.random.default_rng(seed)
    arrays = [{name: float(rng.uniform(-1.0, 1.0)) * (offset_band if name.startswith("mic_")
                                                      else skew_band)
               for name in IMPERFECTIONS} for _ in range(draws)]
    rows = []
    for distance in DISTANCES_M:
        for bearing in BEARINGS_DEG:
            errors = np.array([fix_error(distance, bearing, array) for array in arrays])
            valid = np.isfinite(errors[:, 0])
            rows.append(dict(
                distance_m=distance, bearing_deg=bearing, valid_share=float(valid.mean()),
                range_rms_m=float(np.sqrt(np.mean(errors[valid, 0] ** 2))),
                range_p95_abs_m=float(np.percentile(np.abs(errors[valid, 0]), 95)),
                bearing_rms_deg=float(np.sqrt(np.mean(errors[valid, 1] ** 2))),
                bearing_p95_abs_deg=float(np.percentile(np.abs(errors[valid, 1]), 95))))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--offset-band", type=float, default=1e-3,
                        help="each offset uniform in +- this [m]")
    parser.add_argument("--skew-band", type=float, default=6.7e-6,
                        help="each skew uniform in +- this [s]")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    single = one_at_a_time()
    print("one imperfection at a time: range error [cm] / bearing error [deg]")
    print(f"{'case':40s} " + " ".join(f"{d:g} m {b:g} deg".rjust(17)
                                       for d in DISTANCES_M for b in BEARINGS_DEG[:1]))
    for case in CASES:
        cells = [row for row in single if row["case"] == case and row["bearing_deg"] == 0.0]
        print(f"{case:40s} " + " ".join(
            f"{100 * r['range_error_m']:8.2f} / {r['bearing_error_deg']:6.3f}" for r in cells))
    print("\nat 30 and 60 deg (2 m):")
    for case in CASES:
        cells = [row for row in single if row["case"] == case and row["distance_m"] == 2.0
                 and row["bearing_deg"] > 0.0]
        print(f"{case:40s} " + " ".join(
            f"{100 * r['range_error_m']:8.2f} / {r['bearing_error_deg']:6.3f}" for r in cells))
    spread = random_arrays(args.draws, args.offset_band, args.skew_band)
    print(f"\n{args.draws} random arrays (offsets +-{args.offset_band:g} m, skews "
          f"+-{args.skew_band:g} s): range RMS / 95 % |error| [cm], bearing RMS / 95 % [deg]")
    for row in spread:
        print(f"{row['distance_m']:g} m {row['bearing_deg']:4g} deg: "
              f"{100 * row['range_rms_m']:6.2f} / {100 * row['range_p95_abs_m']:6.2f} cm, "
              f"{row['bearing_rms_deg']:6.3f} / {row['bearing_p95_abs_deg']:6.3f} deg, "
              f"valid {row['valid_share']:.0%}")
    elapsed = time.perf_counter() - started
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "array_imperfections.json"
    out.write_text(json.dumps(dict(
        one_at_a_time=single, random_arrays=dict(draws=args.draws, offset_band_m=args.offset_band,
                                                 skew_band_s=args.skew_band, rows=spread),
        settings=QUIET, seconds=round(elapsed, 1), python=platform.python_version()),
        indent=1, allow_nan=False) + "\n")
    print(f"\n{elapsed:.1f} s; wrote {out}")


if __name__ == "__main__":
    main()

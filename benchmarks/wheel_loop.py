"""Closed-loop wheel-speed comparison on the RobotPlant core: FGS-PD against the paper's CPID.

The paper's Case 1 (Table 6), run by :mod:`orchestrator.verify.case1` (the same code
``sonotrack verify`` judges the paper's overshoot claim with) for every controller form, and
printed as the table of docs/control.md. Run: ``.venv/bin/python benchmarks/wheel_loop.py``.
"""

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from orchestrator.verify.case1 import (  # noqa: E402,F401  (re-exported for the tests)
    CASE1, CONFIGS, SETTLING_BAND, compare, run_case1, trapezoid, wheel_metrics,
)


def main():
    start = time.perf_counter()
    results = compare()
    elapsed = time.perf_counter() - start
    header = f"{'controller':20s} {'wheel':6s} {'overshoot %':>11s} {'settle s':>9s} " \
             f"{'RMS mm/s':>9s} {'mean e mm/s':>11s} {'dither mm/s':>11s}"
    print(header)
    for name, sides in results.items():
        for side, m in sides.items():
            settle = m["settling_time_s"]
            settle = f"{settle:9.2f}" if settle is not None else f"{'never':>9s}"
            print(f"{name:20s} {side:6s} {m['overshoot_percent']:11.2f} "
                  f"{settle} {1e3 * m['rms_error_m_s']:9.2f} "
                  f"{1e3 * m['mean_cruise_error_m_s']:11.2f} {1e3 * m['dither_pp_m_s']:11.2f}")
    out = ROOT / "benchmarks" / "results" / "wheel_loop.json"
    out.write_text(json.dumps({"case": "paper Case 1 (Table 6)", "control_period_s": 0.02,
                               "settling_band": SETTLING_BAND, "configs": CONFIGS,
                               "results": results, "wall_time_s": elapsed}, indent=2) + "\n")
    print(f"wrote {out} ({elapsed:.1f} s)")


if __name__ == "__main__":
    main()

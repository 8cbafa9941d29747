"""Cost of one set + doStep + get of RobotPlant through fmpy against the core in-process.

Both are measured side by side in one run: batches of steps alternate between the FMU and the
core, and the medians over batches are reported with their ratio. Writes
benchmarks/results/fmu_step_cost.json.

    python benchmarks/fmu_step_cost.py [--steps 2000] [--batches 9] [--step-sizes 0.02 0.005]

The first step size (0.02 s, the plant's step in the default scenario) gives the headline
figures; each step size is measured separately.
"""

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import build_fresh, median, write_result  # noqa: E402

OUTPUTS_REAL = ("x", "y", "heading", "wheel_speed_left", "wheel_speed_right", "odom_x", "odom_y",
                "odom_heading", "slip_left", "slip_right", "lateral_slip_speed")
OUTPUTS_INTEGER = ("encoder_left", "encoder_right")


def fmu_batch(instance, inputs, real_out, int_out, t0, h, steps):
    voltages = inputs.values
    started = time.perf_counter()
    for k in range(steps):
        voltages[0] = 6.0
        voltages[1] = 5.0
        instance.write(inputs)
        instance.do_step(t0 + k * h, h)
        instance.read(real_out)
        instance.read(int_out)
    return (time.perf_counter() - started) / steps


def core_batch(core, h, steps):
    started = time.perf_counter()
    for _ in range(steps):
        core.step(6.0, 5.0, h)
        (core.x, core.y, core.heading, core.wheel_speed_left, core.wheel_speed_right,
         core.odom_x, core.odom_y, core.odom_heading, core.slip_left, core.slip_right,
         core.lateral_slip_speed, core.encoder_left, core.encoder_right)
    return (time.perf_counter() - started) / steps


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000, help="steps per batch")
    parser.add_argument("--batches", type=int, default=9, help="batches of each kind")
    parser.add_argument("--step-sizes", type=float, nargs="+", default=[0.02, 0.005],
                        help="communication steps [s]; the first gives the headline figures")
    args = parser.parse_args(argv)

    from components.plant import PlantParameters, RobotPlantCore
    from orchestrator.fmu.handle import FmuInstance

    path = build_fresh(["RobotPlant"])["RobotPlant"]
    cases = []
    for h in args.step_sizes:
        instance = FmuInstance(path, f"bench_{h}")
        instance.instantiate()
        inputs = instance.port_group("Real", ["voltage_left", "voltage_right"])
        real_out = instance.port_group("Real", list(OUTPUTS_REAL))
        int_out = instance.port_group("Integer", list(OUTPUTS_INTEGER))
        core = RobotPlantCore(PlantParameters())
        fmu_times, core_times = [], []
        t0 = 0.0
        for _ in range(args.batches):
            fmu_times.append(fmu_batch(instance, inputs, real_out, int_out, t0, h, args.steps))
            t0 += args.steps * h
            core_times.append(core_batch(core, h, args.steps))
        instance.terminate()
        cases.append({
            "step_size_s": h,
            "fmpy_us_per_step": median(fmu_times) * 1e6,
            "in_process_us_per_step": median(core_times) * 1e6,
            "ratio": median(fmu_times) / median(core_times),
            "fmi_overhead_us_per_step": (median(fmu_times) - median(core_times)) * 1e6,
            "fmpy_us_per_step_batches": [t * 1e6 for t in fmu_times],
            "in_process_us_per_step_batches": [t * 1e6 for t in core_times],
        })
        print(f"RobotPlant, h = {h} s: fmpy {cases[-1]['fmpy_us_per_step']:.1f} us/step, "
              f"in-process {cases[-1]['in_process_us_per_step']:.1f} us/step, "
              f"ratio {cases[-1]['ratio']:.2f}")
    headline = cases[0]
    record = {
        "fmu": "RobotPlant",
        "step_size_s": headline["step_size_s"],
        "steps_per_batch": args.steps,
        "batches": args.batches,
        "fmpy_us_per_step": headline["fmpy_us_per_step"],
        "in_process_us_per_step": headline["in_process_us_per_step"],
        "ratio": headline["ratio"],
        "by_step_size": cases,
        "what": "one set(voltages) + doStep + get(11 Real, 2 Integer outputs) through fmpy's "
                "FMU2Slave with preallocated value-reference arrays, against RobotPlantCore.step "
                "plus reading the same outputs as attributes, in the same process, batches "
                "alternating",
    }
    out = write_result("fmu_step_cost", record)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Accuracy of the AcousticLocalizer against its Cramer-Rao bounds, and in a simulated room.

Monte Carlo over snr_db x distance x bearing (``--trials`` bursts per point, vectorised), the
exact near-field estimator beside the paper's Eq. (4) and the far-field Eq. (5) bearing on the
same delays; then pyroomacoustics shoebox rooms (anechoic and RT60 ~0.3 s) as an independent
signal model; then the localizer's own room (scenarios/room.toml's 7 x 7 x 2.7 m lab, speaker
0.3 m, microphones 0.2 m, bursts every 10 ms): range and bearing RMSE and bias against
distance (0.5-6 m) and RT60 (0 = anechoic, 0.2, 0.3, 0.4, 0.6 s), over ``--room-placements``
random static placements x ``--room-trials`` noise draws each (benchmarks/_room_accuracy.py).
Prints tables, writes ``benchmarks/results/localizer_accuracy.json``, a PNG of RMSE against
the bound over SNR, and ``localizer_accuracy_room.png`` (RMSE and bias against distance).

    .venv/bin/python benchmarks/localizer_accuracy.py [--trials 500] [--rooms 8]
        [--room-placements 16] [--room-trials 25] [--room-only]
"""

import argparse
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

from components.acoustics import (LocalizerSettings, band_derivative_energy, exact_tdoas,
                                  far_field_pair_bearings, locate_bursts, locate_records,
                                  make_estimator, range_bearing_covariance_bound,
                                  tdoa_covariance_bound)

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _room_accuracy  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
SNRS_DB = (0.0, 10.0, 20.0, 30.0)
DISTANCES_M = (1.0, 2.0, 3.0)
BEARINGS_DEG = (0.0, 30.0, 60.0)
ARRAY = np.array([[0.0, 0.4], [0.0, 0.0], [0.0, -0.4]])   # (forward, left) of M1, M2, M3


def rms(values):
    values = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(values**2))) if values.size else float("nan")


def monte_carlo_point(snr_db, distance, bearing_deg, trials, seed):
    """One grid point: errors of every method on the same bursts, and the bounds."""
    settings = LocalizerSettings(snr_db=snr_db)
    spacing, sound = settings.mic_spacing, settings.speed_of_sound
    bearing = math.radians(bearing_deg)
    source = distance * np.array([math.cos(bearing), math.sin(bearing)])
    ranges = np.hypot(*(source - ARRAY).T)
    fixes = locate_bursts(settings, make_estimator("exact", spacing, sound),
                          np.tile(ranges, (trials, 1)), np.random.default_rng(seed))
    true_12, true_23 = (float(v) for v in exact_tdoas(distance, bearing, spacing, sound))
    energy = band_derivative_energy(settings.burst, settings.sample_rate, settings.passband)
    tdoa_cov = tdoa_covariance_bound(ranges, energy, settings.noise_variance)
    bound = range_bearing_covariance_bound(tdoa_cov, true_12, true_23, spacing, sound)
    valid = fixes.valid
    err_12 = fixes.tdoa_12 - true_12
    err_23 = fixes.tdoa_23 - true_23
    # Comparison methods on the very same delays (only where the delays are usable at all).
    paper = make_estimator("paper", spacing, sound).locate(fixes.tdoa_12[valid], fixes.tdoa_23[valid])
    far = make_estimator("far_field", spacing, sound).locate(fixes.tdoa_12[valid], fixes.tdoa_23[valid])
    pair_left, _ = far_field_pair_bearings(sound * fixes.tdoa_12[valid], sound * fixes.tdoa_23[valid],
                                           spacing)
    range_err = fixes.distance[valid] - distance
    bearing_err = np.degrees(fixes.bearing[valid] - bearing)
    paper_range_err = paper.distance - distance
    far_bearing_err = np.degrees(far.bearing - bearing)
    tdoa_crlb = math.sqrt(0.5 * (tdoa_cov[0, 0] + tdoa_cov[1, 1]))
    return {
        "snr_db": snr_db, "distance_m": distance, "bearing_deg": bearing_deg,
        "trials": trials, "valid_fraction": float(valid.mean()),
        # TDOA figures pool both delays (their bounds differ by < 1 % here); over valid fixes,
        # and over every burst (invalid ones included) for the record.
        "tdoa_rmse_s": rms(np.concatenate([err_12[valid], err_23[valid]])),
        "tdoa_rmse_all_s": rms(np.concatenate([err_12, err_23])),
        "tdoa_crlb_s": tdoa_crlb,
        "tdoa_12_rmse_s": rms(err_12[valid]), "tdoa_12_crlb_s": math.sqrt(tdoa_cov[0, 0]),
        "tdoa_23_rmse_s": rms(err_23[valid]), "tdoa_23_crlb_s": math.sqrt(tdoa_cov[1, 1]),
        "tdoa_correlation_crlb": float(tdoa_cov[0, 1] / math.sqrt(tdoa_cov[0, 0] * tdoa_cov[1, 1])),
        "range_rmse_m": rms(range_err), "range_bias_m": float(np.mean(range_err)) if range_err.size else float("nan"),
        "range_crlb_m": math.sqrt(bound[0, 0]),
        "bearing_rmse_deg": rms(bearing_err), "bearing_bias_deg": float(np.mean(bearing_err)) if bearing_err.size else float("nan"),
        "bearing_crlb_deg": math.degrees(math.sqrt(bound[1, 1])),
        "eq4_range_rmse_m": rms(paper_range_err[paper.consistent]),
        "eq4_range_bias_m": float(np.mean(paper_range_err[paper.consistent])) if paper.consistent.any() else float("nan"),
        "far_field_bearing_rmse_deg": rms(far_bearing_err[far.consistent]),
        "far_field_bearing_bias_deg": float(np.mean(far_bearing_err[far.consistent])) if far.consistent.any() else float("nan"),
        "eq5a_pair_bearing_rmse_deg": rms(np.degrees(pair_left - bearing)),
    }


def room_errors(rt60, rooms, seed):
    """Bearing and range errors on pyroomacoustics signals, robot placed at ``rooms`` spots."""
    import pyroomacoustics as pra

    settings = LocalizerSettings(snr_db=30.0)
    estimator = make_estimator("exact", settings.mic_spacing, settings.speed_of_sound)
    fs = int(settings.sample_rate)
    room_dim = [7.0, 7.0, 3.0]
    height = 0.25
    rng = np.random.default_rng(seed)
    pra.constants.set("c", settings.speed_of_sound)
    lead = pra.constants.get("frac_delay_length") // 2
    burst = settings.burst.waveform(np.arange(int(settings.burst_duration * fs) + 1) / fs)
    rows = []
    for distance in DISTANCES_M:
        for bearing_deg in BEARINGS_DEG:
            bearing_errors, range_errors, valid = [], [], 0
            for _ in range(rooms):
                # Robot somewhere in the room facing +y, source ahead inside the walls.
                centre = np.array([rng.uniform(3.0, 4.0), rng.uniform(0.8, 1.5)])
                side = rng.choice([-1.0, 1.0])
                b = math.radians(bearing_deg) * side
                source = centre + distance * np.array([-math.sin(b), math.cos(b)])
                if rt60 is None:
                    room = pra.ShoeBox(room_dim, fs=fs, max_order=0, air_absorption=False)
                else:
                    absorption, order = pra.inverse_sabine(rt60, room_dim)
                    room = pra.ShoeBox(room_dim, fs=fs, materials=pra.Material(absorption),
                                       max_order=order)
                room.add_source([source[0], source[1], height],
                                signal=np.concatenate([burst, np.zeros(64)]))
                mics = np.array([[centre[0] - 0.4, centre[1], height], [centre[0], centre[1], height],
                                 [centre[0] + 0.4, centre[1], height]]).T
                room.add_microphone_array(pra.MicrophoneArray(mics, fs))
                room.simulate()
                signals = room.mic_array.signals
                signals = 0.4 * signals / np.abs(signals).max()
                first = int(np.floor(np.min(np.hypot(*(mics[:2].T - source).T))
                                     / settings.speed_of_sound * fs))
                padded = np.concatenate([np.zeros((3, 200)), signals], axis=1)
                start = 200 + first + lead - int(settings.pre_roll * fs)
                records = padded[:, start:start + settings.record_samples]
                records = records + 1e-3 * rng.standard_normal(records.shape)
                fixes = locate_records(settings, estimator, records[None])
                if fixes.valid[0]:
                    valid += 1
                    bearing_errors.append(math.degrees(fixes.bearing[0] - b))
                    range_errors.append(fixes.distance[0] - distance)
            rows.append({
                "rt60_s": rt60, "distance_m": distance, "bearing_deg": bearing_deg,
                "rooms": rooms, "valid_fraction": valid / rooms,
                "bearing_rmse_deg": rms(bearing_errors),
                "bearing_max_abs_deg": float(np.max(np.abs(bearing_errors))) if bearing_errors else float("nan"),
                "range_rmse_m": rms(range_errors),
                "range_max_abs_m": float(np.max(np.abs(range_errors))) if range_errors else float("nan"),
            })
    return rows


def plot(records, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    quantities = (("tdoa_rmse_s", "tdoa_crlb_s", 1e6, "TDOA RMSE [us]"),
                  ("range_rmse_m", "range_crlb_m", 1e2, "range RMSE [cm]"),
                  ("bearing_rmse_deg", "bearing_crlb_deg", 1.0, "bearing RMSE [deg]"))
    colours = {1.0: "tab:blue", 2.0: "tab:orange", 3.0: "tab:green"}
    for axis, (rmse, crlb, scale, label) in zip(axes, quantities):
        for distance in DISTANCES_M:
            for bearing_deg, marker in zip(BEARINGS_DEG, "os^"):
                rows = [r for r in records if r["distance_m"] == distance
                        and r["bearing_deg"] == bearing_deg]
                snr = [r["snr_db"] for r in rows]
                axis.semilogy(snr, [r[rmse] * scale for r in rows], marker=marker,
                              color=colours[distance], linestyle="none",
                              label=f"{distance:g} m, {bearing_deg:g} deg")
                axis.semilogy(snr, [r[crlb] * scale for r in rows], color=colours[distance],
                              linestyle="-" if bearing_deg == 0 else ":", linewidth=0.8)
        axis.set_xlabel("snr_db (at 1 m)")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    axes[0].set_title("markers: Monte Carlo RMSE; lines: Cramer-Rao bound")
    axes[2].legend(fontsize=7, ncol=1)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=500, help="bursts per grid point")
    parser.add_argument("--rooms", type=int, default=8, help="room placements per room point")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--room-placements", type=int, default=16,
                        help="static placements per distance x RT60 in the localizer's room")
    parser.add_argument("--room-trials", type=int, default=25,
                        help="noise draws per placement in the localizer's room")
    parser.add_argument("--room-only", action="store_true",
                        help="only the localizer's room (keeps the other sections of the JSON)")
    args = parser.parse_args(argv)
    if args.room_only:
        return room_only(args)
    started = time.perf_counter()
    records = []
    seed = args.seed
    for snr_db in SNRS_DB:
        for distance in DISTANCES_M:
            for bearing_deg in BEARINGS_DEG:
                seed += 1
                records.append(monte_carlo_point(snr_db, distance, bearing_deg, args.trials, seed))
    print(f"{'snr':>4} {'D':>4} {'brg':>4} {'valid':>6} {'tdoa/crlb':>9} {'range cm':>9} "
          f"{'crlb':>6} {'brg deg':>8} {'crlb':>6} {'Eq4 cm':>8} {'ff deg':>7} {'5a deg':>7}")
    for r in records:
        print(f"{r['snr_db']:4.0f} {r['distance_m']:4.1f} {r['bearing_deg']:4.0f} "
              f"{r['valid_fraction']:6.3f} {r['tdoa_rmse_s'] / r['tdoa_crlb_s']:9.2f} "
              f"{100 * r['range_rmse_m']:9.2f} {100 * r['range_crlb_m']:6.2f} "
              f"{r['bearing_rmse_deg']:8.3f} {r['bearing_crlb_deg']:6.3f} "
              f"{100 * r['eq4_range_rmse_m']:8.1f} {r['far_field_bearing_rmse_deg']:7.2f} "
              f"{r['eq5a_pair_bearing_rmse_deg']:7.2f}")
    monte_carlo_s = time.perf_counter() - started
    rooms = room_errors(None, args.rooms, args.seed) + room_errors(0.3, args.rooms, args.seed + 1)
    print(f"\n{'rt60':>5} {'D':>4} {'brg':>4} {'valid':>6} {'brg rmse':>9} {'brg max':>8} "
          f"{'rng rmse':>9} {'rng max':>8}")
    for r in rooms:
        print(f"{str(r['rt60_s']):>5} {r['distance_m']:4.1f} {r['bearing_deg']:4.0f} "
              f"{r['valid_fraction']:6.2f} {r['bearing_rmse_deg']:9.3f} "
              f"{r['bearing_max_abs_deg']:8.3f} {r['range_rmse_m']:9.3f} {r['range_max_abs_m']:8.3f}")

    high = [r for r in records if r["snr_db"] >= 10.0]
    worst = max(high, key=lambda r: r["tdoa_rmse_s"] / r["tdoa_crlb_s"])
    point = next(r for r in records if r["snr_db"] == 20.0 and r["distance_m"] == 2.0
                 and r["bearing_deg"] == 0.0)
    anechoic_2m = [r for r in rooms if r["rt60_s"] is None and r["distance_m"] == 2.0]
    targets = {
        "tdoa_rmse_over_crlb_max_snr_ge_10": worst["tdoa_rmse_s"] / worst["tdoa_crlb_s"],
        "tdoa_rmse_over_crlb_max_at": [worst["snr_db"], worst["distance_m"], worst["bearing_deg"]],
        "tdoa_rmse_all_over_crlb_max_snr_ge_10": max(r["tdoa_rmse_all_s"] / r["tdoa_crlb_s"] for r in high),
        "tdoa_target_ratio": 1.3,
        "range_rmse_m_2m_broadside_20db": point["range_rmse_m"], "range_target_m": 0.03,
        "bearing_rmse_deg_2m_broadside_20db": point["bearing_rmse_deg"], "bearing_target_deg": 0.5,
        "anechoic_room_bearing_max_abs_deg_2m": max(r["bearing_max_abs_deg"] for r in anechoic_2m),
        "anechoic_room_bearing_target_deg": 1.0,
    }
    print(f"\nTDOA RMSE / bound, worst over snr_db >= 10 (valid fixes): "
          f"{targets['tdoa_rmse_over_crlb_max_snr_ge_10']:.3f} at {targets['tdoa_rmse_over_crlb_max_at']} "
          f"(all bursts: {targets['tdoa_rmse_all_over_crlb_max_snr_ge_10']:.3f}; target <= 1.3)")
    print(f"2 m broadside 20 dB: range RMSE {point['range_rmse_m']:.4f} m (target <= 0.03), "
          f"bearing RMSE {point['bearing_rmse_deg']:.4f} deg (target <= 0.5)")
    print(f"anechoic room, 2 m: worst bearing error {targets['anechoic_room_bearing_max_abs_deg_2m']:.3f} deg "
          f"(target <= 1)")
    room_started = time.perf_counter()
    room = _room_accuracy.measure(args.room_placements, args.room_trials, args.seed + 7)
    _room_accuracy.print_tables(room)
    room_s = time.perf_counter() - room_started
    elapsed = time.perf_counter() - started
    print(f"Monte Carlo {monte_carlo_s:.1f} s, localizer's room {room_s:.1f} s, "
          f"total {elapsed:.1f} s")

    RESULTS.mkdir(parents=True, exist_ok=True)
    settings = LocalizerSettings()
    result = {
        "description": "AcousticLocalizer accuracy vs Cramer-Rao bounds; RMSE over valid fixes",
        "command": f"benchmarks/localizer_accuracy.py --trials {args.trials} --rooms {args.rooms} "
                   f"--room-placements {args.room_placements} --room-trials {args.room_trials} "
                   f"--seed {args.seed}",
        "settings": settings.as_dict(),
        "records": records,
        "rooms": rooms,
        "targets": targets,
        "room_accuracy": room,
        "runtime_s": elapsed,
        "machine": {"python": platform.python_version(), "processor": platform.machine()},
    }
    path = RESULTS / "localizer_accuracy.json"
    path.write_text(json.dumps(result, indent=2, allow_nan=True) + "\n")
    plot(records, RESULTS / "localizer_accuracy.png")
    _room_accuracy.plot(room, RESULTS / "localizer_accuracy_room.png")
    print(f"wrote {path}, {path.with_suffix('.png')} and localizer_accuracy_room.png")
    return result


def room_only(args):
    """Measure only the localizer's room and replace that section of an existing JSON."""
    started = time.perf_counter()
    room = _room_accuracy.measure(args.room_placements, args.room_trials, args.seed + 7)
    _room_accuracy.print_tables(room)
    path = RESULTS / "localizer_accuracy.json"
    result = json.loads(path.read_text()) if path.exists() else {}
    result["room_accuracy"] = room
    result["room_command"] = (f"benchmarks/localizer_accuracy.py --room-only --room-placements "
                              f"{args.room_placements} --room-trials {args.room_trials} "
                              f"--seed {args.seed}")
    RESULTS.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=2, allow_nan=True) + "\n")
    _room_accuracy.plot(room, RESULTS / "localizer_accuracy_room.png")
    print(f"localizer's room {time.perf_counter() - started:.1f} s; wrote {path} (room_accuracy) "
          f"and localizer_accuracy_room.png")
    return result


if __name__ == "__main__":
    main()

"""The localizer in its own room: range and bearing RMSE and bias against distance and RT60.

The room of scenarios/room.toml (7 x 7 x 2.7 m, speaker 0.3 m and microphones 0.2 m above the
floor, a burst every 10 ms, image sources to the -30 dB time cut) at RT60 0 (every surface
absorbs all: the direct sound alone, at the two heights), 0.2, 0.3, 0.4 and 0.6 s; snr_db 20.
For each distance the same random static placements serve every RT60 (robot anywhere in the
room at any heading, source at that distance within +-60 deg of its heading, both 0.3 m from
the walls), each with its own noise draws. Errors are of valid fixes against the horizontal
distance and bearing from M2; ``max_range`` is raised to 8 m so that 6 m is measured. Besides
the steady state (every earlier burst's reverberation), one burst alone at RT60 0.4 s, and the
time cut at 20 and 40 dB, show what the earlier bursts and the cut change.

Used by benchmarks/localizer_accuracy.py.
"""

import math

import numpy as np

from components.acoustics import (LocalizerSettings, RoomAcoustics, locate_records,
                                  make_estimator, quantise)

DISTANCES_M = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
RT60_S = (0.0, 0.2, 0.3, 0.4, 0.6)
CUTS_DB = (20.0, 40.0)            # beside the grid's 30 dB, at RT60 0.4 s
MAX_BEARING_DEG = 60.0
ROOM = dict(room=True, room_origin_x=-3.5, room_origin_y=-0.5, room_length_x=7.0,
            room_length_y=7.0, room_height=2.7, source_height=0.3, mic_height=0.2,
            burst_period=0.01, reverb_cut_db=30.0, max_range=8.0)
MARGIN_M = 0.3


def settings_for(rt60, **extra):
    """The benchmark's localizer settings at ``rt60`` (0: every surface absorbs everything)."""
    parameters = dict(ROOM, **extra)
    if rt60 == 0.0:
        parameters.update(absorption_walls=1.0, absorption_floor=1.0, absorption_ceiling=1.0)
    else:
        parameters["rt60"] = rt60
    return LocalizerSettings(**parameters)


def placements(acoustics, distance, count, rng):
    """``count`` (source, microphones, bearing) in room coordinates, bodies inside the room."""
    size = acoustics.room.size
    origin = acoustics.room.origin
    chosen = []
    while len(chosen) < count:
        x, y = rng.uniform(MARGIN_M, size[0] - MARGIN_M), rng.uniform(MARGIN_M, size[1] - MARGIN_M)
        heading = rng.uniform(0.0, 2.0 * math.pi)
        bearing = math.radians(rng.uniform(-MAX_BEARING_DEG, MAX_BEARING_DEG))
        mics = acoustics.microphones(x + origin[0], y + origin[1], heading)
        source = mics[1, :2] + distance * np.array([math.cos(heading + bearing),
                                                    math.sin(heading + bearing)])
        points = np.vstack([mics[:, :2], source])
        if np.all(points > MARGIN_M) and np.all(points < size[:2] - MARGIN_M):
            chosen.append((np.array([*source, acoustics.source_height]), mics, bearing))
    return chosen


def point(rt60, distance, places, trials, seed, earlier=True, **extra):
    """Errors at one distance and RT60 over the placements, ``trials`` noise draws each."""
    settings = settings_for(rt60, **extra)
    acoustics = RoomAcoustics(settings)
    estimator = make_estimator("exact", settings.mic_spacing, settings.speed_of_sound)
    rng = np.random.default_rng(seed)
    range_errors, bearing_errors, biases, valid = [], [], [], 0
    for source, mics, bearing in places:
        clean, _ = acoustics.static_records(source, mics, earlier=earlier)
        noisy = clean + settings.noise_std * rng.standard_normal((trials,) + clean.shape)
        fixes = locate_records(settings, estimator, quantise(noisy, settings.adc_bits))
        ok = fixes.valid
        valid += int(ok.sum())
        error = fixes.distance[ok] - distance
        range_errors.append(error)
        bearing_errors.append(np.degrees(fixes.bearing[ok] - bearing))
        if error.size:
            biases.append(float(error.mean()))
    range_errors = np.concatenate(range_errors)
    bearing_errors = np.concatenate(bearing_errors)

    def stat(values, how):
        return float(how(values)) if values.size else float("nan")

    return {
        "rt60_s": rt60, "distance_m": distance, "earlier_bursts": earlier,
        "reverb_cut_db": settings.reverb_cut_db, "placements": len(places), "trials": trials,
        "valid_fraction": valid / (len(places) * trials),
        "range_rmse_m": stat(range_errors, lambda v: np.sqrt(np.mean(v**2))),
        "range_bias_m": stat(range_errors, np.mean),
        "range_placement_bias_std_m": stat(np.array(biases), np.std),
        "bearing_rmse_deg": stat(bearing_errors, lambda v: np.sqrt(np.mean(v**2))),
        "bearing_bias_deg": stat(bearing_errors, np.mean),
    }


def measure(placement_count, trials, seed):
    """Every row: the RT60 x distance grid, one burst alone, and the other time cuts."""
    geometry = settings_for(0.4)
    rows = []
    for d_index, distance in enumerate(DISTANCES_M):
        places = placements(RoomAcoustics(geometry), distance, placement_count,
                            np.random.default_rng(seed + d_index))
        noise_seed = seed + 1000 * (d_index + 1)
        for rt60 in RT60_S:
            rows.append(point(rt60, distance, places, trials, noise_seed))
        rows.append(point(0.4, distance, places, trials, noise_seed, earlier=False))
        if distance in (2.0, 5.0):
            for cut in CUTS_DB:
                rows.append(point(0.4, distance, places, trials, noise_seed,
                                  reverb_cut_db=cut))
    return {"description": __doc__.split("\n\n")[1].replace("\n", " "), "rows": rows,
            "snr_db": geometry.snr_db, "room": {k: v for k, v in ROOM.items()}}


def print_tables(room):
    print(f"\n{'rt60':>5} {'D':>4} {'bursts':>6} {'cut':>4} {'valid':>6} {'rng rmse cm':>11} "
          f"{'rng bias cm':>11} {'plc bias sd':>11} {'brg rmse':>9} {'brg bias':>9}")
    for r in room["rows"]:
        print(f"{r['rt60_s']:5.2f} {r['distance_m']:4.1f} "
              f"{'train' if r['earlier_bursts'] else 'one':>6} {r['reverb_cut_db']:4.0f} "
              f"{r['valid_fraction']:6.3f} {100 * r['range_rmse_m']:11.2f} "
              f"{100 * r['range_bias_m']:11.2f} {100 * r['range_placement_bias_std_m']:11.2f} "
              f"{r['bearing_rmse_deg']:9.3f} {r['bearing_bias_deg']:9.3f}")


def grid_rows(room):
    """The steady-state rows at the default cut, by (rt60, distance)."""
    return {(r["rt60_s"], r["distance_m"]): r for r in room["rows"]
            if r["earlier_bursts"] and r["reverb_cut_db"] == ROOM["reverb_cut_db"]}


def plot(room, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = grid_rows(room)
    figure, axes = plt.subplots(2, 2, figsize=(12, 8), sharex=True)
    panels = (("range_rmse_m", 100.0, "range RMSE [cm]"), ("range_bias_m", 100.0,
                                                           "range bias [cm]"),
              ("bearing_rmse_deg", 1.0, "bearing RMSE [deg]"),
              ("bearing_bias_deg", 1.0, "bearing bias [deg]"))
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, len(RT60_S)))
    single = sorted((r for r in room["rows"] if not r["earlier_bursts"]),
                    key=lambda r: r["distance_m"])
    for axis, (field, scale, label) in zip(axes.ravel(), panels):
        for rt60, colour in zip(RT60_S, colours):
            values = [grid[(rt60, d)][field] * scale for d in DISTANCES_M]
            axis.plot(DISTANCES_M, values, marker="o", color=colour,
                      label="anechoic" if rt60 == 0.0 else f"RT60 {rt60:g} s")
        axis.plot([r["distance_m"] for r in single], [r[field] * scale for r in single],
                  linestyle="--", color="tab:red", label="RT60 0.4 s, one burst alone")
        if "bias" in field:
            axis.axhline(0.0, color="black", linewidth=0.6)
        else:
            axis.set_yscale("log")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    for axis in axes[1]:
        axis.set_xlabel("distance [m]")
    axes[0, 0].set_title("localizer in the 7 x 7 x 2.7 m room, bursts every 10 ms, 20 dB at 1 m")
    axes[0, 1].legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)

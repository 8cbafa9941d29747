"""Per-run figures of a synthetic record: arrival and own-plan keys, each defined."""

import math

import numpy as np
import pytest

from orchestrator.reproduce.measures import DEFINITIONS, arrival_figures, tracking_figures
from orchestrator.reproduce.runs import RunRecord

DT = 0.02


def straight_run(stop_y=1.0, target_y=1.0, offset=0.0, creep=0.0):
    """Drives up the y axis at 0.4 m/s to ``stop_y``, stands (or creeps at ``creep`` m/s)
    until 6 s; ``offset`` shifts the path sideways after the first fix. The source stands at
    (0, target_y), heard exactly every 100 ms."""
    time = np.arange(0, 6.0 + DT / 2, DT)
    y = np.minimum(0.4 * time, stop_y)
    stopped = time > stop_y / 0.4
    y = y + creep * np.where(stopped, time - stop_y / 0.4, 0.0)
    x = np.where(time > 0.0, offset, 0.0)
    speed = np.gradient(y, time)
    ids = np.floor(time / 0.1 + 1e-9) + 1
    n = len(time)
    data = {
        "time": time, "plant.x": x, "plant.y": y, "plant.heading": np.full(n, 0.5 * math.pi),
        "source.x": np.zeros(n), "source.y": np.full(n, target_y), "source.emitting": np.ones(n),
        "planner.radius": np.full(n, 1e6), "planner.curvature": np.zeros(n),
        "planner.v_ref_left": speed, "planner.v_ref_right": speed,
        "plant.rim_speed_left": speed, "plant.rim_speed_right": speed,
        "plant.slip_left": np.zeros(n), "plant.slip_right": np.zeros(n),
        "localizer.measurement_id": ids, "localizer.valid": np.ones(n),
        "localizer.distance": np.abs(target_y - y), "localizer.bearing": np.zeros(n),
    }
    # hold each fix between fixes, as the localizer does
    first = np.searchsorted(ids, ids, side="left")
    data["localizer.distance"] = data["localizer.distance"][first]
    return RunRecord("cell", 0, {"status": "ok"}, data, "", {"planner.mode": "curvature"})


def test_arrival_figures_judge_at_arrival_and_keep_the_final_error():
    reference = np.array([[0.0, 0.0], [0.0, 1.0]])
    figures = arrival_figures(straight_run(stop_y=0.97), reference)
    assert figures["arrived"] == 1.0 and figures["arrival_s"] == pytest.approx(0.97 / 0.4,
                                                                               abs=DT)
    # at rest from the sample whose last step (2 mm) lies inside the 5 mm rest band
    assert figures["error_at_arrival_m"] == pytest.approx(0.03, abs=0.4 * DT)
    assert figures["error_m"] == pytest.approx(0.03)
    # it ends where it stops: the drift is the last 2 mm, along the line to the target
    assert figures["drift_after_arrival_m"] == pytest.approx(
        figures["error_at_arrival_m"] - figures["error_m"], abs=1e-12)
    assert figures["rmse_own_plan_m"] == pytest.approx(0.0, abs=1e-12)
    # creeping on at 5 mm/s after arriving: the creep is the drift, the end error grows
    creeping = arrival_figures(straight_run(stop_y=0.97, creep=0.002), reference)
    assert creeping["arrived"] == 1.0
    # arrived at y = 0.968 m (t = 2.42 s), then the last 2 mm and 3.575 s of creep
    assert creeping["arrival_s"] == pytest.approx(2.42)
    assert creeping["drift_after_arrival_m"] == pytest.approx(
        0.002 + 0.002 * (6.0 - 0.97 / 0.4), abs=1e-9)
    # stopping 0.3 m short never arrives within 0.1 m: counted, no arrival figures
    short = arrival_figures(straight_run(stop_y=0.7), reference)
    assert short["arrived"] == 0.0 and short["arrival_s"] is None
    assert short["error_m"] == pytest.approx(0.3)
    # or arrives with the caller's wider tolerance
    assert arrival_figures(straight_run(stop_y=0.7), reference, tolerance=0.35)["arrived"] == 1


def test_own_plan_figure_of_an_offset_path():
    figures = arrival_figures(straight_run(offset=0.02), np.array([[0.0, 0.0], [0.0, 1.0]]))
    # the plans start on the offset line from the second fix on; before that, the path runs
    # 0.02 m off the first plan (laid from the origin) for 0.1 s
    assert 0.0 < figures["rmse_own_plan_m"] < 0.02


def test_every_arrival_figure_and_the_new_tracking_ones_have_a_definition():
    run = straight_run()
    keys = set(arrival_figures(run, np.array([[0.0, 0.0], [0.0, 1.0]]))) - {"turn_deg"}
    tracking = tracking_figures(run, 0.0)
    assert {"rmse_own_plan_m", "settle_s"} <= set(tracking)
    keys |= {"rmse_own_plan_m", "settle_s"}
    assert keys <= set(DEFINITIONS), sorted(keys - set(DEFINITIONS))

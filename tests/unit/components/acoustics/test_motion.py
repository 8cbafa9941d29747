"""The localizer's record of recent inputs: interpolation, silence before the start, trimming."""

import numpy as np
import pytest

from components.acoustics.motion import PoseHistory


def filled(horizon=0.05, steps=20, step=0.01):
    history = PoseHistory(horizon)
    for k in range(steps):
        t = k * step
        history.record(t, 1.0 + 0.2 * t, -0.5 * t, k >= 3, 0.1 * t, 0.0, 1.0 + t)
    return history


def test_positions_between_steps_are_linear_and_held_outside():
    table = filled(horizon=1.0).table()
    times = np.array([-1.0, 0.0, 0.015, 0.1234, 0.19, 5.0])
    expected_x = 1.0 + 0.2 * np.clip(times, 0.0, 0.19)
    expected_y = -0.5 * np.clip(times, 0.0, 0.19)
    np.testing.assert_allclose(PoseHistory.source_at(table, times),
                               np.c_[expected_x, expected_y], rtol=0, atol=1e-15)
    # One instant at a time: the same values, to the bit (the room's emission instant is
    # iterated on them).
    for time, x, y, row in zip(times, expected_x, expected_y, PoseHistory.source_at(table, times)):
        assert PoseHistory.source_point(table, time) == pytest.approx((x, y), rel=0, abs=1e-15)
        assert PoseHistory.source_point(table, time) == tuple(row.tolist())


def test_emitting_is_sample_and_hold_and_silent_before_the_first_sample():
    table = filled(horizon=1.0).table()
    times = np.array([-0.001, 0.0, 0.029, 0.03, 0.0301, 0.5])
    np.testing.assert_array_equal(PoseHistory.emitting_at(table, times),
                                  [False, False, False, True, True, True])


def test_only_the_horizon_and_one_older_sample_are_kept():
    history = filled(horizon=0.05)
    times = [sample[0] for sample in history.samples]
    assert times[0] <= 0.19 - 0.05 < times[1]
    assert times[-1] == pytest.approx(0.19)
    assert len(times) == 6


def test_a_repeated_time_replaces_the_later_samples():
    history = filled(horizon=1.0, steps=5)
    history.record(0.02, 9.0, 9.0, True, 9.0, 9.0, 9.0)
    assert [s[0] for s in history.samples] == [0.0, 0.01, 0.02]
    assert history.samples[-1][1] == 9.0


def test_latest_two_robot_poses():
    (t0, x0, y0, h0), (t1, x1, y1, h1) = PoseHistory.latest_two(filled(horizon=1.0).table())
    assert (t0, t1) == pytest.approx((0.18, 0.19))
    assert (x0, x1, h1) == pytest.approx((0.018, 0.019, 1.19))

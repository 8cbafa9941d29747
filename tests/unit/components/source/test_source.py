"""The moving source: path geometry, speed limits, continuity, end point, muting."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from components.common.errors import ParameterError
from components.source import MovingSource, make_path

STEP = 0.01


def sample(source, duration, step=STEP):
    rows = []
    for k in range(int(round(duration / step)) + 1):
        source.advance_to(k * step)
        rows.append((source.x, source.y, source.vx, source.vy, source.emitting,
                     source.burst_count, source.progress))
    return rows


def s_curve_offset(u, amplitude, length):
    """Lateral offset of docs/source.md, written out again for the test."""
    phase = math.pi * u / length
    return amplitude * 16 / (3 * math.sqrt(3)) * math.sin(phase) ** 3 * math.cos(phase)


def test_straight_path_is_six_metres_from_one_to_seven():
    path = make_path("straight")
    assert path.length == pytest.approx(6.0)
    assert path.position(0.0) == pytest.approx((0.0, 1.0))
    assert path.position(path.length) == pytest.approx((0.0, 7.0))


def test_s_curve_length_matches_the_arc_length_integral():
    amplitude, length = 0.5, 6.0
    path = make_path("s_curve", amplitude=amplitude, length=length)
    h = 1e-6

    def slope(u):
        return (s_curve_offset(u + h, amplitude, length)
                - s_curve_offset(u - h, amplitude, length)) / (2 * h)

    expected, _ = quad(lambda u: math.hypot(1.0, slope(u)), 0.0, length, limit=200)
    assert path.length == pytest.approx(expected, rel=1e-6)
    # The S swings A to the left at u = l/3 and A to the right at 2l/3 (robot facing +y: left = -x).
    xs = [path.position(s)[0] for s in np.linspace(0, path.length, 3001)]
    assert min(xs) == pytest.approx(-amplitude, abs=1e-4)
    assert max(xs) == pytest.approx(amplitude, abs=1e-4)
    assert path.position(path.length) == pytest.approx((0.0, 7.0), abs=1e-12)


@pytest.mark.parametrize("name", ["straight", "s_curve"], ids=["straight", "s_curve"])
def test_points_lie_on_the_curve_at_their_arc_length(name):
    path = make_path(name)
    previous = path.position(0.0)
    for s in np.linspace(0.0, path.length, 2001)[1:]:
        x, y = path.position(s)
        assert x == pytest.approx(s_curve_offset(y - 1.0, 0.5, 6.0) * -1.0 if name == "s_curve"
                                  else 0.0, abs=1e-9)
        # Consecutive chords are no longer than the arc between them (arc-length parametrisation).
        chord = math.hypot(x - previous[0], y - previous[1])
        assert chord <= path.length / 2000 * (1 + 1e-6)
        assert chord >= path.length / 2000 * 0.999
        previous = (x, y)


@pytest.mark.parametrize("name", ["straight", "s_curve"], ids=["straight", "s_curve"])
def test_speed_and_acceleration_limits_and_continuity(name):
    v_max, a_max = 0.2, 0.2
    source = MovingSource(name, v_max=v_max, a_max=a_max)
    rows = np.array(sample(source, source.end_time + 2.0), dtype=float)
    positions, velocities = rows[:, 0:2], rows[:, 2:4]
    steps = np.hypot(*np.diff(positions, axis=0).T)
    assert steps.max() <= v_max * STEP * (1 + 1e-9)                 # never faster than v_max
    speeds = np.hypot(*velocities.T)
    assert speeds.max() == pytest.approx(v_max, rel=1e-9)
    assert np.abs(np.diff(speeds)).max() <= a_max * STEP * (1 + 1e-9)
    # Reported velocity agrees with the motion (central differences), so x, y are continuous.
    centre = (positions[2:] - positions[:-2]) / (2 * STEP)
    assert np.abs(centre - velocities[1:-1]).max() < 5e-3


@pytest.mark.parametrize("mute", [True, False], ids=["muted", "keeps-sounding"])
def test_end_point_reached_and_mute_at_end(mute):
    source = MovingSource("straight", mute_at_end=mute, start_delay=1.0)
    # Rest-to-rest trapezoid: T = L / v + v / a = 6 / 0.2 + 1 = 31 s, plus the delay.
    assert source.end_time == pytest.approx(32.0)
    rows = sample(source, 40.0)
    assert rows[int(31.0 / STEP)][0:2] == pytest.approx((0.0, 1.0 + 6.0 - 0.1), abs=1e-9)
    assert rows[-1][0:2] == pytest.approx((0.0, 7.0), abs=1e-12)
    assert rows[-1][2:4] == (0.0, 0.0)
    before_end = [row[4] for row in rows if row[6] < 6.0]
    after_end = [row[4] for k, row in enumerate(rows) if k * STEP > 32.0 + 1e-9]
    assert all(before_end)
    assert all(not e for e in after_end) if mute else all(after_end)


def test_bursts_every_emit_period():
    source = MovingSource("static", emit_period=0.01)
    source.advance_to(1.0)
    assert source.burst_count == 101                  # bursts at 0, 0.01, ..., 1.00
    assert source.last_burst_time == pytest.approx(1.0)
    assert source.emitting and (source.vx, source.vy) == (0.0, 0.0)
    assert (source.x, source.y) == (0.0, 1.0)


def test_csv_waypoints(tmp_path):
    csv = tmp_path / "square.csv"
    csv.write_text("# a 1 m leg and a 2 m leg\nx,y\n0,1\n0,2\n\n2,2\n")
    source = MovingSource(str(csv))
    assert source.path.length == pytest.approx(3.0)
    source.advance_to(source.end_time)
    assert (source.x, source.y) == pytest.approx((2.0, 2.0))


@pytest.mark.parametrize("text, line", [("x,y\n0,1\n0,two\n", 3), ("0,1\n1,2,3\n", 2),
                                        ("0,1\nnan,2\n", 2)],
                         ids=["word", "three-columns", "nan"])
def test_bad_csv_row_names_file_and_line(tmp_path, text, line):
    csv = tmp_path / "bad.csv"
    csv.write_text(text)
    with pytest.raises(ParameterError, match=rf"bad\.csv, line {line}"):
        MovingSource(str(csv))


def test_unknown_path_lists_the_valid_choices():
    with pytest.raises(ParameterError, match="straight.*s_curve.*static"):
        MovingSource("zigzag")
    with pytest.raises(ParameterError, match="cannot read"):
        MovingSource("/nonexistent/waypoints.csv")


def test_static_source_moves_to_its_second_position_at_switch_time():
    from components.source import MovingSource

    source = MovingSource(path="static", x0=0.5, y0=0.5, x1=1.5, y1=1.0, switch_time=4.0)
    source.advance_to(3.99)
    assert (source.x, source.y) == (0.5, 0.5)
    source.advance_to(4.0)
    assert (source.x, source.y) == (1.5, 1.0)
    assert source.emitting


def test_switch_time_on_a_moving_path_is_refused_with_the_valid_choice():
    from components.common.errors import ParameterError
    from components.source import MovingSource

    with pytest.raises(ParameterError, match="switch_time = 2.0 applies to path 'static'"):
        MovingSource(path="straight", switch_time=2.0)

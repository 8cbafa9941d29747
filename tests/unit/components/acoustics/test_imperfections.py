"""The array's imperfections: microphones off their places, ADC channels sampled apart.

One concept across geometry.py (true positions), synthesis.py (skewed sampling),
reverberation.py (the room heard at the true positions and instants) and localizer.py (the
nominal estimator on those records). The reference is tests/support/array_geometry.py: the
true delays from positions, and the nominal array's equations solved by scipy.

Tolerance: with 24 bits and 120 dB (no noise to speak of) the localizer's delays on the
nominal array are exact to 2e-11 s (2e-6 of the 10 us sample period: the band-limited
correlation's Newton steps leave no fractional bias; measured over 1-4 m, +-60 deg).
TDOA_TOLERANCE = 1e-9 s (1e-4 of a sample) is 50 times that and 1/1000 of the effects tested
(1 mm of path is 2.9 us); range and bearing get the tolerance's effect through the geometry.
"""

import math

import numpy as np
import pytest

from components.acoustics import LocalizerCore, LocalizerSettings, make_estimator
from components.acoustics.localizer import locate_bursts
from components.acoustics.reverberation import RoomAcoustics
from components.acoustics.synthesis import _synthesise
from components.common.errors import ParameterError
from components.common.faults import Fault, encode_schedule

from tests.support.array_geometry import (fix_tolerance, nominal_fix, skewed_tdoas, source_at,
                                          true_microphones)

TDOA_TOLERANCE = 1e-9
QUIET = dict(snr_db=120.0, adc_bits=24, seed=0)
POSE = (0.3, -0.4, 1.3)            # not along an axis: the offsets' frame is the robot's

OFFSET_NAMES = (("mic_left_along", "mic_left_across"), ("mic_centre_along", "mic_centre_across"),
                ("mic_right_along", "mic_right_across"))


def offsets_of(parameters):
    return tuple((parameters.get(along, 0.0), parameters.get(across, 0.0))
                 for along, across in OFFSET_NAMES)


def skews_of(parameters):
    return (parameters.get("adc_skew_left", 0.0), 0.0, parameters.get("adc_skew_right", 0.0))


def one_fix(distance, bearing, pose=POSE, **parameters):
    core = LocalizerCore(**QUIET, **parameters)
    source = source_at(pose, distance, bearing)
    core.step(0.0, 0.01, source[0], source[1], True, *pose)
    return core


def reference(distance, bearing, parameters, pose=POSE):
    """True delays of the imperfect array and the nominal fix they give, with its tolerance."""
    source = source_at(pose, distance, bearing)
    delays = skewed_tdoas(source, true_microphones(pose, offsets_of(parameters)),
                          skews_of(parameters))
    fix = nominal_fix(*delays, guess=(distance, bearing))
    nominal = skewed_tdoas(source, true_microphones(pose))
    return delays, fix, fix_tolerance(*delays, TDOA_TOLERANCE, guess=(distance, bearing)), nominal


CASES = {
    "centre_forward_1mm_2m": (2.0, 0.0, dict(mic_centre_across=1e-3)),
    "centre_forward_1mm_3m": (3.0, 0.0, dict(mic_centre_across=1e-3)),
    "left_along_5mm_left30": (2.5, math.radians(30), dict(mic_left_along=5e-3)),
    "right_back_3mm_right40": (1.5, math.radians(-40), dict(mic_right_across=-3e-3)),
    "centre_along_2mm_left10": (2.0, math.radians(10), dict(mic_centre_along=2e-3)),
    "outer_channels_early_2m": (2.0, 0.0, dict(adc_skew_left=-3.3e-6, adc_skew_right=-3.3e-6)),
    "outer_channels_early_3m": (3.0, 0.0, dict(adc_skew_left=-3.3e-6, adc_skew_right=-3.3e-6)),
    "multiplexed_left20": (2.0, math.radians(20), dict(adc_skew_left=-3.3e-6,
                                                       adc_skew_right=3.3e-6)),
    "everything_right50": (1.5, math.radians(-50), dict(
        mic_left_along=-4e-3, mic_left_across=2e-3, mic_centre_along=1e-3,
        mic_centre_across=-6e-3, mic_right_along=9e-3, mic_right_across=3e-3,
        adc_skew_left=12e-6, adc_skew_right=-7e-6)),
    # A fault sends the records through faults.faulted_records: the same true delays.
    "with_a_gain_fault_left15": (2.0, math.radians(15), dict(
        mic_centre_across=2e-3, mic_right_along=-5e-3, adc_skew_left=-6e-6, adc_skew_right=4e-6,
        fault_schedule=encode_schedule([Fault("mic_gain", 0.0, magnitude=1.2, channel="M1")]))),
}


@pytest.mark.parametrize("distance, bearing, parameters", CASES.values(), ids=CASES.keys())
def test_the_fix_is_the_nominal_geometry_s_answer_to_the_true_delays(distance, bearing,
                                                                     parameters):
    core = one_fix(distance, bearing, **parameters)
    (tdoa_12, tdoa_23), (fix_distance, fix_bearing), (range_tol, bearing_tol), nominal = \
        reference(distance, bearing, parameters)
    assert core.valid
    assert core.tdoa_12 == pytest.approx(tdoa_12, abs=TDOA_TOLERANCE)
    assert core.tdoa_23 == pytest.approx(tdoa_23, abs=TDOA_TOLERANCE)
    assert core.distance == pytest.approx(fix_distance, abs=range_tol)
    assert core.bearing == pytest.approx(fix_bearing, abs=bearing_tol)
    # The imperfection moves a delay by far more than the tolerance: records that ignored it
    # (the nominal array's delays) would fail the assertions above.
    shift = max(abs(tdoa_12 - nominal[0]), abs(tdoa_23 - nominal[1]))
    assert shift > 1000.0 * TDOA_TOLERANCE
    # The truth outputs stay the nominal array's: the imperfection is the localizer's error.
    assert core.true_distance == pytest.approx(distance, abs=1e-12)


# The issue's figures (two significant figures) and the exact geometry's, at broadside.
ISSUE_FIGURES = {
    "centre_1mm_forward_2m": (2.0, dict(mic_centre_across=1e-3), -0.05, -0.0502),
    "centre_1mm_forward_3m": (3.0, dict(mic_centre_across=1e-3), -0.11, -0.1098),
    "outer_3.3us_early_2m": (2.0, dict(adc_skew_left=-3.3e-6, adc_skew_right=-3.3e-6),
                             -0.057, -0.0562),
    "outer_3.3us_early_3m": (3.0, dict(adc_skew_left=-3.3e-6, adc_skew_right=-3.3e-6),
                             -0.124, -0.1228),
}


@pytest.mark.parametrize("distance, parameters, issue, exact", ISSUE_FIGURES.values(),
                         ids=ISSUE_FIGURES.keys())
def test_the_issue_s_range_errors_come_from_the_centre_microphone_and_channel(
        distance, parameters, issue, exact):
    error = one_fix(distance, 0.0, pose=(0.0, 0.0, math.pi / 2), **parameters).distance - distance
    assert error == pytest.approx(exact, abs=1e-4)
    # The issue's skew figures are 1-2 % beyond the exact geometry's; its offsets' agree.
    assert error == pytest.approx(issue, rel=0.025)
    # One outer microphone alone moves a + b by half as much: half the error.
    if "mic_centre_across" in parameters:
        alone = one_fix(distance, 0.0, pose=(0.0, 0.0, math.pi / 2), mic_left_across=-1e-3)
        assert alone.distance - distance == pytest.approx(exact / 2.0, rel=0.02)


def test_with_noise_the_mean_error_is_the_geometric_one():
    # The default 20 dB and 10-bit ADC: the bias survives the noise (the Monte Carlo's case).
    parameters = dict(mic_centre_across=1e-3, adc_skew_left=2e-6)
    settings = LocalizerSettings(seed=3, **parameters)
    estimator = make_estimator("exact", settings.mic_spacing, settings.speed_of_sound)
    pose = (0.0, 0.0, math.pi / 2)
    source = source_at(pose, 2.0, math.radians(20))
    ranges = np.hypot(*(source - true_microphones(pose, offsets_of(parameters))).T)
    fixes = locate_bursts(settings, estimator, np.tile(ranges, (400, 1)),
                          np.random.default_rng(3))
    assert fixes.valid.all()
    _, (fix_distance, fix_bearing), _, _ = reference(2.0, math.radians(20), parameters, pose)
    spread = np.std(fixes.distance) / math.sqrt(400)
    assert np.mean(fixes.distance) == pytest.approx(fix_distance, abs=4.0 * spread)
    assert abs(fix_distance - 2.0) > 20.0 * spread
    assert np.mean(fixes.bearing) == pytest.approx(
        fix_bearing, abs=4.0 * np.std(fixes.bearing) / math.sqrt(400))


# ----- the synthesis samples each channel at its own instants ----------------------------------
def test_a_skewed_channel_is_the_burst_at_the_skewed_instants():
    settings = LocalizerSettings()
    ranges = np.array([2.03, 2.0, 1.98])
    skews = (4.7e-6, 0.0, -13.1e-6)
    n = settings.record_samples
    records = _synthesise(settings.burst, ranges, sample_rate=settings.sample_rate,
                          speed_of_sound=settings.speed_of_sound, noise_std=0.0, adc_bits=24,
                          pre_roll=settings.pre_roll, n_samples=n,
                          rng=np.random.default_rng(0), adc_skews=skews)
    arrivals = ranges / settings.speed_of_sound
    start = math.floor((arrivals.min() - settings.pre_roll) * settings.sample_rate) \
        / settings.sample_rate
    for mic in range(3):
        instants = start + np.arange(n) / settings.sample_rate + skews[mic]
        expected = 0.5 / ranges[mic] * settings.burst.waveform(instants - arrivals[mic])
        # 24 bits: the ADC's half step, 6e-8, is all that may differ.
        assert np.abs(records[mic] - expected).max() <= 2.0 ** -24
        if skews[mic]:
            unskewed = 0.5 / ranges[mic] * settings.burst.waveform(instants - skews[mic]
                                                                   - arrivals[mic])
            assert np.abs(records[mic] - unskewed).max() > 1e-3


# ----- the room hears the true positions and instants --------------------------------------------
IMPERFECT = dict(mic_left_along=4e-3, mic_left_across=-2e-3, mic_centre_across=5e-3,
                 mic_right_along=-3e-3, mic_right_across=7e-3, adc_skew_left=-9e-6,
                 adc_skew_right=5e-6)


def test_the_room_s_microphones_are_the_true_ones():
    acoustics = RoomAcoustics(LocalizerSettings(room=True, mic_height=0.2, **IMPERFECT))
    mics = acoustics.microphones(*POSE)
    expected = true_microphones(POSE, offsets_of(IMPERFECT)) - np.array([-3.5, -0.5])
    np.testing.assert_allclose(mics[:, :2], expected, atol=1e-15)
    assert (mics[:, 2] == 0.2).all()


def test_a_reverberant_room_is_rendered_at_the_true_positions_and_skewed_instants():
    # The imperfect array's records equal the perfect array's renderer given the true
    # microphones, each channel's record started skew_i late: every image and every earlier
    # burst is heard where the microphones are and when each channel samples.
    imperfect = RoomAcoustics(LocalizerSettings(room=True, rt60=0.3, reverb_cut_db=20.0,
                                                **IMPERFECT))
    perfect = RoomAcoustics(LocalizerSettings(room=True, rt60=0.3, reverb_cut_db=20.0))
    source = np.array([2.7, 3.9, 0.3])
    mics = imperfect.microphones(*POSE)
    records, ranges = imperfect.static_records(source, mics)
    np.testing.assert_allclose(ranges, np.linalg.norm(mics - source, axis=1), rtol=1e-15)
    count = imperfect.earlier_bursts + 1
    reference_time = float(np.linalg.norm(mics[1] - source)) / perfect.speed_of_sound
    sounded = np.ones(count, dtype=bool)
    start = math.floor((min(ranges) / perfect.speed_of_sound - perfect.pre_roll)
                       * perfect.sample_rate) / perfect.sample_rate
    window = (start - perfect.burst_duration - 1e-4, start + perfect.n_samples / FS + 1e-4)
    arrivals = perfect.arrivals(np.tile(source, (count, 1)), sounded, mics, np.zeros((3, 3)),
                                reference_time, window)
    skews = skews_of(IMPERFECT)
    for mic in range(3):
        mine = arrivals.microphone == mic
        alone = perfect.renderer.render(np.zeros(int(mine.sum()), dtype=int),
                                        arrivals.delay[mine], arrivals.gain[mine],
                                        start + skews[mic], perfect.n_samples)[0]
        assert np.abs(records[mic] - alone).max() <= 1e-12
    nominal = perfect.static_records(source, perfect.microphones(*POSE))[0]
    assert np.abs(records - nominal).max() > 0.05


FS = 100e3


def test_an_anechoic_room_gives_the_free_field_fix_of_the_imperfect_array():
    # Speaker and microphones at one height: the room's direct sound is the free field's, to
    # the renderer's 5 ns of delay (rendering.py); hence 20 ns here.
    room = dict(room=True, absorption_walls=1.0, absorption_floor=1.0, absorption_ceiling=1.0,
                source_height=0.25, mic_height=0.25)
    distance, bearing, pose = 2.2, math.radians(25), (0.3, 0.6, 1.3)
    core = one_fix(distance, bearing, pose, **room, **IMPERFECT)
    (tdoa_12, tdoa_23), (fix_distance, fix_bearing), _, _ = reference(distance, bearing,
                                                                      IMPERFECT, pose)
    range_tol, bearing_tol = fix_tolerance(tdoa_12, tdoa_23, 2e-8, guess=(distance, bearing))
    assert core.valid
    assert core.tdoa_12 == pytest.approx(tdoa_12, abs=2e-8)
    assert core.tdoa_23 == pytest.approx(tdoa_23, abs=2e-8)
    assert core.distance == pytest.approx(fix_distance, abs=range_tol)
    assert core.bearing == pytest.approx(fix_bearing, abs=bearing_tol)


# ----- defaults: the code before the imperfections, bit for bit ----------------------------------
def _trace(core, moving=0.0):
    out = []
    for k in range(31):
        core.step(k * 0.01, 0.01, -0.9 + moving * k, 2.3 + 0.003 * k, True, 0.1, -0.2, 1.4)
        if k % 10 == 0:
            out.append(tuple(float(v).hex() for v in (core.tdoa_12, core.tdoa_23, core.distance,
                                                       core.bearing)))
    return out[-1]


FAULTS = encode_schedule([Fault("reflecting_wall", 0.0, magnitude=0.6),
                          Fault("mic_gain", 0.0, magnitude=1.3, channel="M3")])
ROOM = dict(room=True, rt60=0.3, reverb_cut_db=20.0)
# The last of four fixes (t = 0, 0.1, 0.2, 0.3 s), as the code gave them before the
# imperfections existed (commit 016181f): every noise draw and every fix before it counts.
BEFORE = {
    "free_field": (dict(seed=7, snr_db=10.0), 0.0, (
        "-0x1.18a3d21e1a527p-11", "0x1.5d4528c94067fp-11", "0x1.52c126e4ee713p+1",
        "0x1.14f1b0fce30b3p-1")),
    "faults": (dict(seed=7, snr_db=10.0, fault_schedule=FAULTS), 0.0, (
        "-0x1.18a3d21e1a527p-11", "0x1.5e1d3b010c942p-11", "0x1.4e495164c695cp+1",
        "0x1.156c324430389p-1")),
    "room": (dict(seed=7, snr_db=20.0, **ROOM), 0.002, (
        "-0x1.0abbe15ffdcc2p-11", "0x1.51d1a4873acb1p-11", "0x1.501828a7ace39p+1",
        "0x1.08c2173b5c2bep-1")),
    "room_faults": (dict(seed=7, snr_db=20.0, fault_schedule=FAULTS, **ROOM), 0.002, (
        "-0x1.0abbe15ffdcc2p-11", "0x1.5253c24eccd6ap-11", "0x1.4d825372faf0bp+1",
        "0x1.090a7beda2defp-1")),
}


@pytest.mark.parametrize("parameters, moving, before", BEFORE.values(), ids=BEFORE.keys())
@pytest.mark.parametrize("explicit", [False, True], ids=["omitted", "zeros"])
def test_a_perfect_array_gives_the_earlier_fixes_bit_for_bit(parameters, moving, before,
                                                              explicit):
    zeros = {name: 0.0 for pair in OFFSET_NAMES for name in pair}
    zeros.update(adc_skew_left=0.0, adc_skew_right=0.0)
    assert _trace(LocalizerCore(**parameters, **(zeros if explicit else {})), moving) == before


def test_the_batched_path_of_a_perfect_array_is_unchanged_bit_for_bit():
    settings = LocalizerSettings(seed=5, snr_db=10.0)
    estimator = make_estimator("exact", 0.4, 340.0)
    geometry = np.random.default_rng(3)
    distance, bearing = geometry.uniform(1, 4, 20), geometry.uniform(-1, 1, 20)
    source = np.stack([distance * np.sin(bearing), distance * np.cos(bearing)], -1)
    mics = np.array([[-0.4, 0.0], [0.0, 0.0], [0.4, 0.0]])
    ranges = np.hypot(*(source[:, None, :] - mics[None]).transpose(2, 0, 1))
    fixes = locate_bursts(settings, estimator, ranges, np.random.default_rng(5))
    assert [float(np.nansum(v)).hex() for v in (fixes.tdoa_12, fixes.tdoa_23, fixes.distance)] \
        == ["0x1.703419a0aae20p-10", "0x1.abe5fc3e7b5bcp-10", "0x1.7fb245449e8c1p+5"]


# ----- valid ranges ----------------------------------------------------------------------------
@pytest.mark.parametrize("name, value, valid", [
    ("mic_centre_across", 0.011, "[-0.01, 0.01] m"),
    ("mic_left_along", -0.5, "[-0.01, 0.01] m"),
    ("adc_skew_right", 2.5e-5, "[-2e-05, 2e-05] s"),
    ("adc_skew_left", math.nan, "[-2e-05, 2e-05] s"),
], ids=["across", "along", "skew", "nan"])
def test_an_imperfection_outside_its_range_is_refused_naming_it_and_the_range(name, value, valid):
    with pytest.raises(ParameterError) as caught:
        LocalizerSettings(**{name: value})
    assert f"{name} = {value!r}" in str(caught.value)
    assert f"outside its valid range {valid}" in str(caught.value)

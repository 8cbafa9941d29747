"""Each fault's own effect on the one core it targets, against what the fault means physically."""

import math

import numpy as np
import pytest

from components.acoustics.faults import channel_fault, faulted_records, mirror_in_wall
from components.acoustics.localizer import FixStatus, LocalizerCore
from components.acoustics.settings import LocalizerSettings
from components.acoustics.synthesis import noise_std
from components.common.faults import Fault, encode_schedule
from components.planner.planner import REACQUIRE_AFTER, FIX_REJECTED, TargetPlanner
from components.plant.plant import RobotPlantCore
from components.source.source import MovingSource

_RANGES = (2.05, 2.0, 1.96)


def _records(faults, image=None, seed=5, **settings):
    s = LocalizerSettings(**settings)
    return s, faulted_records(s, _RANGES, image, faults, np.random.default_rng(seed))


def test_dead_microphone_zeroes_its_channel_only_and_no_fix_comes_from_it():
    _, records = _records([Fault("mic_dead", 0.0, channel="M2")])
    assert not records[1].any()
    assert records[0].std() > 0 and records[2].std() > 0
    assert channel_fault(records, 10) == (1, None)
    core = LocalizerCore(fault_schedule=encode_schedule([Fault("mic_dead", 0.5, channel="M2")]))
    statuses = []
    for k in range(10):
        core.step(0.1 * k, 0.1, 0.3, 2.0, True, 0.0, 0.0, math.pi / 2)
        statuses.append((core.fix_status, core.valid, core.measurement_id))
    assert all(valid for _, valid, _ in statuses[:5])
    assert all(status == FixStatus.DEAD_MICROPHONE and not valid
               for status, valid, _ in statuses[5:])
    assert statuses[-1][2] == 5   # no fix counted from the dead channel


def test_clipping_flattens_the_channel_at_the_level():
    _, clean = _records([])
    _, clipped = _records([Fault("mic_clipping", 0.0, magnitude=0.05, channel="M3")])
    step = 2.0 / 2**10
    assert np.abs(clipped[2]).max() <= 0.05 + step / 2
    assert np.count_nonzero(np.abs(clipped[2]) >= 0.05 - step) > 20
    np.testing.assert_array_equal(clipped[:2], clean[:2])
    assert channel_fault(clipped, 10) == (None, 2)
    assert channel_fault(clean, 10) == (None, None)


def test_gain_error_scales_the_channel_before_the_adc():
    s, low = _records([Fault("mic_gain", 0.0, magnitude=0.25, channel="M1")], adc_bits=24)
    _, clean = _records([], adc_bits=24)
    np.testing.assert_allclose(low[0], 0.25 * clean[0], atol=2 * 2.0 / 2**24)
    np.testing.assert_array_equal(low[1:], clean[1:])


def test_low_snr_sets_the_noise_of_its_snr():
    s, records = _records([Fault("low_snr", 0.0, magnitude=0.0)], adc_bits=24)
    pre_roll = int(0.8e-3 * s.sample_rate)       # before the earliest arrival: noise only
    measured = records[:, :pre_roll].std()
    expected = noise_std(s.burst, 0.0, s.sample_rate)
    assert measured == pytest.approx(expected, rel=0.1)
    assert expected > 5 * s.noise_std


def test_impulsive_noise_adds_clicks_of_the_magnitude():
    _, clean = _records([], adc_bits=24)
    _, clicks = _records([Fault("impulsive_noise", 0.0, magnitude=0.8)], adc_bits=24)
    extra = clicks - clean
    # three decaying clicks per channel, each starting at +-0.8 (they may overlap)
    assert np.all(np.abs(extra).max(axis=1) >= 0.8 - 1e-6)


def test_reflecting_wall_adds_the_image_source_burst():
    s = LocalizerSettings(adc_bits=24)
    wall_x = 0.3
    image = mirror_in_wall(0.0, 2.0, wall_x)
    assert image == (0.6, 2.0)
    image_ranges = (2.12, 2.09, 2.07)
    rng_a, rng_b = np.random.default_rng(1), np.random.default_rng(1)
    with_wall = faulted_records(s, _RANGES, image_ranges, [Fault("reflecting_wall", 0.0,
                                                              magnitude=wall_x)], rng_a)
    without = faulted_records(s, _RANGES, None, [], rng_b)
    echo = with_wall - without
    first = min(_RANGES) / s.speed_of_sound - s.pre_roll
    start = math.floor(first * s.sample_rate) / s.sample_rate
    times = start + np.arange(s.record_samples) / s.sample_rate
    for mic, distance in enumerate(image_ranges):
        expected = 0.9 * 0.5 / distance * s.burst.waveform(times - distance / s.speed_of_sound)
        np.testing.assert_allclose(echo[mic], expected, atol=1e-6)


def test_lost_fixes_drop_every_other_attempt():
    core = LocalizerCore(fault_schedule=encode_schedule([Fault("lost_fixes", 0.0, 1.0, 0.5)]))
    statuses = []
    for k in range(14):
        core.step(0.1 * k, 0.1, 0.3, 2.0, True, 0.0, 0.0, math.pi / 2)
        statuses.append(core.fix_status)
    assert statuses[:10:2] == [FixStatus.OK] * 5
    assert statuses[1:10:2] == [FixStatus.FIX_LOST] * 5
    assert statuses[10:] == [FixStatus.OK] * 4


def test_source_silent_mutes_bursts_and_keeps_moving():
    schedule = encode_schedule([Fault("source_silent", 1.0, 2.0)])
    quiet, loud = MovingSource(fault_schedule=schedule), MovingSource()
    for t in (0.5, 1.0, 1.5, 2.0, 2.5):
        quiet.advance_to(t)
        loud.advance_to(t)
        assert quiet.emitting == (not 1.0 <= t < 2.0)
        assert (quiet.x, quiet.y) == (loud.x, loud.y)
    assert loud.burst_count - quiet.burst_count == 100   # 1.00 .. 1.99 s at 10 ms


def _drive(core, volts, seconds, step=0.02):
    for _ in range(round(seconds / step)):
        core.step(volts, volts, step)


def test_supply_sag_limits_the_applied_voltage():
    core = RobotPlantCore(fault_schedule=encode_schedule(
        [Fault("supply_sag", 0.2, 0.4, 4.0, "left")]))
    _drive(core, 11.0, 0.2)
    assert core.voltage_left == 11.0
    _drive(core, 11.0, 0.1)
    assert core.voltage_left == 4.0 and core.voltage_right == 11.0 and core.clamped


def test_encoder_freeze_and_skip_lose_counts():
    frozen = RobotPlantCore(fault_schedule=encode_schedule(
        [Fault("encoder_freeze", 0.5, 1.0, channel="right"),
         Fault("encoder_skip", 0.5, 1.0, 0.5, "left")]))
    _drive(frozen, 6.0, 0.5)
    right_before, left_before = frozen.encoder_right, frozen.encoder_left
    true_left_before = frozen.left_encoder.count
    _drive(frozen, 6.0, 0.5)
    assert frozen.encoder_right == right_before and frozen.wheel_speed_right == 0.0
    true_left = frozen.left_encoder.count - true_left_before
    assert abs((frozen.encoder_left - left_before) - 0.5 * true_left) <= 1
    assert frozen.right_encoder.count > right_before + 100   # the wheel did turn


def test_low_friction_patch_lowers_mu_under_the_wheel_in_the_region_only():
    patch = Fault("low_friction", 0.0, magnitude=0.1, channel="both", region=(0.0, 0.3, 1.0, 5.0))
    core = RobotPlantCore(fault_schedule=encode_schedule([patch]))
    nominal = core.tyre_peak
    _drive(core, 2.0, 0.2)
    assert core.y < 0.3 and core.tyre_peak_left == core.tyre_peak_right == nominal
    # the right wheel (x = +0.1445 at the start heading) is in the region once y >= 0.3
    while core.y < 0.35:
        core.step(3.0, 3.0, 0.02)
    assert core.tyre_peak_right == pytest.approx(0.1 / core.parameters.mu * nominal)
    assert core.tyre_peak_left == nominal       # x = -0.1445, outside [0, 1]


def test_planner_gate_rejects_a_jump_and_reacquires():
    planner = TargetPlanner(max_target_speed=1.0, target_jump_margin=0.3)
    planner.update(0.0, 0.02, 0.0, 0.0, 1, True, 2.0, 0.0)
    assert planner.has_target and planner.target_y == pytest.approx(2.0)
    # 0.1 s later the target is 1.0 m away: needs 10 m/s; rejected
    planner.update(0.1, 0.02, 0.0, 0.0, 2, True, 3.0, 0.0)
    assert planner.fix_outcome == FIX_REJECTED and planner.rejected_fixes == 1
    # 0.35 m away after 0.1 s: within 1.0 * 0.1 + 0.3 = 0.4 m
    planner.update(0.2, 0.02, 0.0, 0.0, 3, True, 2.35, 0.0)
    assert planner.fix_outcome == "accepted"
    for k in range(REACQUIRE_AFTER):
        planner.update(0.3 + 0.1 * k, 0.02, 0.0, 0.0, 4 + k, True, 4.0, 0.0)
        assert planner.fix_outcome == FIX_REJECTED
    planner.update(1.0, 0.02, 0.0, 0.0, 20, True, 4.0, 0.0)
    assert planner.fix_outcome == "accepted" and planner.rejected_fixes == 1 + REACQUIRE_AFTER


def test_planner_slows_to_half_cruise_without_fixes():
    planner = TargetPlanner(v_cruise=0.3, fix_timeout=1.0)
    planner.update(0.0, 0.02, 0.0, 0.0, 1, True, 3.0, 0.0)
    speeds = []
    for k in range(1, 150):
        left, right = planner.update(0.02 * k, 0.02, planner.v_ref_left, planner.v_ref_right)
        speeds.append(left)
    assert max(speeds[:45]) == pytest.approx(0.3)
    assert not planner.timed_out or speeds[-1] <= 0.15 + 1e-12
    assert speeds[-1] == pytest.approx(0.15)


def test_on_a_low_friction_patch_the_body_accelerates_at_most_mu_g():
    # Friction bounds the traction force by mu N per wheel: the body cannot gain speed faster
    # than mu g, whatever the motors do (an independent bound on the integrated dynamics).
    mu, seconds = 0.02, 0.5
    patch = Fault("low_friction", 0.0, magnitude=mu, channel="both", region=(-2.0, -1.0, 2.0, 1.0))
    iced = RobotPlantCore(fault_schedule=encode_schedule([patch]))
    dry = RobotPlantCore()
    _drive(iced, 11.0, seconds)
    _drive(dry, 11.0, seconds)
    gravity = iced.parameters.gravity
    assert iced.speed <= mu * gravity * seconds * 1.01
    assert iced.speed >= 0.5 * mu * gravity * seconds       # it does push at the limit
    assert iced.slip_left > 0.5                               # the wheels spin
    assert dry.speed > 3 * mu * gravity * seconds and abs(dry.slip_left) < 0.2


def test_state_restored_mid_fault_replays_exactly():
    # The schedule is a constant of the instance (not saved); everything a fault changes is.
    from components.common.state import restore, snapshot

    schedule = encode_schedule([Fault("impulsive_noise", 0.2, 0.8, 0.8),
                                Fault("lost_fixes", 0.0, 1.0, 0.5)])
    first, second = LocalizerCore(fault_schedule=schedule), LocalizerCore(fault_schedule=schedule)
    for k in range(4):
        first.step(0.1 * k, 0.1, 0.3, 2.0, True, 0.0, 0.0, math.pi / 2)
    restore(second, snapshot(first))
    for k in range(4, 10):
        for core in (first, second):
            core.step(0.1 * k, 0.1, 0.3, 2.0, True, 0.0, 0.0, math.pi / 2)
        assert (first.fix_status, first.distance, first.bearing) == (
            second.fix_status, second.distance, second.bearing)
    plant_schedule = encode_schedule([Fault("encoder_skip", 0.1, 1.0, 0.3, "left")])
    plant_a = RobotPlantCore(fault_schedule=plant_schedule)
    plant_b = RobotPlantCore(fault_schedule=plant_schedule)
    _drive(plant_a, 6.0, 0.3)
    restore(plant_b, snapshot(plant_a))
    _drive(plant_a, 6.0, 0.3)
    _drive(plant_b, 6.0, 0.3)
    assert plant_a.encoder_left == plant_b.encoder_left and plant_a.left_encoder.lost > 0
    assert plant_a.left_encoder.carry == plant_b.left_encoder.carry

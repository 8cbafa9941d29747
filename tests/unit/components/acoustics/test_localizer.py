"""The stateful localizer core: fix timing, holding, refusals, determinism, state round trip."""

import json
import math

import numpy as np
import pytest

from components.acoustics import FixStatus, LocalizerCore, LocalizerSettings
from components.common.errors import InputError, ParameterError
from components.common.state import restore, snapshot

# Robot at the origin facing +y (heading pi/2): "left" is -x.
POSE = dict(robot_x=0.0, robot_y=0.0, robot_heading=math.pi / 2)


def run(core, source, emitting=True, steps=1, h=0.01, t0=0.0):
    for k in range(steps):
        core.step(t0 + k * h, h, source[0], source[1], emitting, **POSE)


def test_valid_fix_near_truth_and_ids_count_fixes():
    core = LocalizerCore(snr_db=30.0, seed=3)
    source = (-2.0 * math.sin(0.4), 2.0 * math.cos(0.4))   # 2 m, 0.4 rad to the left
    run(core, source, steps=25)                            # t = 0 .. 0.24 s: instants 0, 0.1, 0.2
    assert core.measurement_id == 3
    assert core.valid
    assert core.distance == pytest.approx(2.0, abs=0.02)
    assert core.bearing == pytest.approx(0.4, abs=math.radians(0.2))
    assert core.true_distance == pytest.approx(2.0, abs=1e-12)
    assert core.true_bearing == pytest.approx(0.4, abs=1e-12)


def test_fix_instants_from_time_not_step_count():
    core = LocalizerCore(snr_db=30.0)
    taken = []
    h = 0.03
    for k in range(12):                     # t = 0 .. 0.33: instants 0, 0.1, 0.2, 0.3
        taken.append(core.step(k * h, h, 0.0, 2.0, True, **POSE))
    assert [k * h for k, t in enumerate(taken) if t] == pytest.approx([0.0, 0.09, 0.18, 0.3])


def test_holds_last_fix_when_not_emitting():
    core = LocalizerCore(snr_db=30.0)
    run(core, (0.0, 2.0), steps=1)
    held = (core.distance, core.bearing, core.tdoa_12, core.measurement_id)
    run(core, (0.0, 3.0), emitting=False, steps=20, t0=0.01)
    assert (core.distance, core.bearing, core.tdoa_12, core.measurement_id) == held
    assert not core.valid
    assert core.fix_status == FixStatus.NOT_EMITTING


@pytest.mark.parametrize("source, status", [
    ((0.0, 0.0), FixStatus.TOO_CLOSE),
    ((0.0, -2.0), FixStatus.BEHIND),
    ((0.0, 9.0), FixStatus.OUT_OF_RANGE),
], ids=["at_centre", "straight_behind", "beyond_range"])
def test_unhearable_source_gives_invalid_without_exception(source, status):
    core = LocalizerCore(snr_db=30.0)
    run(core, (0.5, 2.0), steps=1)
    first = core.distance
    run(core, source, steps=11, t0=0.01)
    assert not core.valid
    assert core.fix_status == status
    assert core.distance == first and core.measurement_id == 1


def test_non_finite_input_names_port_and_value():
    core = LocalizerCore()
    with pytest.raises(InputError, match=r"robot_heading = inf"):
        core.step(0.0, 0.01, 0.0, 2.0, True, 0.0, 0.0, float("inf"))


def test_invalid_parameters_reported_together():
    with pytest.raises(ParameterError) as info:
        LocalizerSettings(weighting="scot", method="music", window=1e-3, adc_bits=40)
    message = str(info.value)
    for fragment in ("weighting = 'scot'", "method = 'music'", "adc_bits = 40", "window = 0.001"):
        assert fragment in message


def test_same_seed_is_bit_identical_and_seeds_differ():
    outputs = []
    for seed in (5, 5, 6):
        core = LocalizerCore(seed=seed, snr_db=10.0)
        run(core, (-1.0, 2.0), steps=31)
        outputs.append((core.tdoa_12, core.tdoa_23, core.distance, core.bearing))
    assert outputs[0] == outputs[1]
    assert outputs[0] != outputs[2]


def test_snapshot_restore_through_json_repeats_the_future():
    core = LocalizerCore(seed=9, snr_db=10.0)
    run(core, (-1.0, 2.0), steps=15)
    saved = json.loads(json.dumps(snapshot(core)))
    run(core, (-1.0, 2.5), steps=30, t0=0.15)
    first = (core.tdoa_12, core.tdoa_23, core.distance, core.measurement_id, core.last_fix_index)
    restore(core, saved)
    run(core, (-1.0, 2.5), steps=30, t0=0.15)
    assert (core.tdoa_12, core.tdoa_23, core.distance, core.measurement_id,
            core.last_fix_index) == first


@pytest.mark.parametrize("settings", [
    dict(snr_db=20.0), dict(snr_db=0.0), dict(snr_db=10.0, weighting="phat"),
    dict(snr_db=40.0, method="paper"), dict(snr_db=10.0, method="far_field", adc_bits=8),
], ids=["20dB", "0dB", "phat", "paper", "far-field-8bit"])
def test_scalar_single_burst_path_equals_the_batched_path_bit_for_bit(settings):
    # The core takes a fix through _locate_one (Python scalars, for speed); the batched
    # locate_bursts is the reference implementation of the same steps and random draws.
    from components.acoustics.estimators import make_estimator
    from components.acoustics.localizer import _locate_one, locate_bursts

    s = LocalizerSettings(seed=5, **settings)
    estimator = make_estimator(s.method, s.mic_spacing, s.speed_of_sound)
    geometry = np.random.default_rng(11)
    rng_one, rng_batch = np.random.default_rng(s.seed), np.random.default_rng(s.seed)
    statuses = set()
    for _ in range(150):
        r, bearing = geometry.uniform(0.5, 4.5), geometry.uniform(-1.4, 1.4)
        source = np.array([r * math.sin(bearing), r * math.cos(bearing)])
        mics = np.array([[-s.mic_spacing, 0.0], [0.0, 0.0], [s.mic_spacing, 0.0]])
        ranges = np.hypot(*(source - mics).T)
        one = _locate_one(s, estimator, [float(x) for x in ranges], rng_one)
        batch = locate_bursts(s, estimator, ranges, rng_batch)
        statuses.add(int(batch.status))
        assert int(one.status) == int(batch.status)
        for name in ("tdoa_12", "tdoa_23", "quality"):
            assert float(getattr(one, name)) == float(getattr(batch, name)), name
        if int(batch.status) == FixStatus.OK:
            assert float(one.distance) == float(batch.distance)
            assert float(one.bearing) == float(batch.bearing)
    assert rng_one.bit_generator.state == rng_batch.bit_generator.state
    if settings.get("snr_db") == 0.0:
        assert len(statuses) > 1, "0 dB should exercise failed fixes too"


# ----- in a room -------------------------------------------------------------------------------
def room_run(core, steps, source=(-0.5, 2.5), t0=0.0, h=0.01):
    for k in range(steps):
        core.step(t0 + k * h, h, source[0], source[1] + 0.002 * k, True, **POSE)


def test_free_field_ignores_the_room_parameters_bit_for_bit():
    plain = LocalizerCore(seed=3, snr_db=10.0)
    dressed = LocalizerCore(seed=3, snr_db=10.0, room=False, rt60=0.5, mic_height=1.0,
                            source_height=0.7, room_origin_x=-1.0, burst_period=0.02)
    assert dressed.acoustics is None and dressed.history is None
    for core in (plain, dressed):
        run(core, (-1.0, 2.0), steps=41)
    states = [snapshot(core)["__object__"] for core in (plain, dressed)]
    for state in states:
        del state["settings"]          # the parameters themselves differ
    assert states[0] == states[1]
    assert states[0]["measurement_id"] == 5


def test_anechoic_room_at_one_height_gives_the_free_field_fixes():
    # Same seed, same noise draws: the records differ by the rendering's 5e-4 of the burst.
    free = LocalizerCore(seed=4, snr_db=20.0)
    room = LocalizerCore(seed=4, snr_db=20.0, room=True, absorption_walls=1.0,
                         absorption_floor=1.0, absorption_ceiling=1.0, source_height=0.25,
                         mic_height=0.25)
    for k in range(51):
        for core in (free, room):
            core.step(k * 0.01, 0.01, -0.7, 2.4, True, **POSE)
        if k % 10 == 0:
            assert room.fix_status == free.fix_status == FixStatus.OK
            assert room.distance == pytest.approx(free.distance, abs=2e-3)
            assert room.bearing == pytest.approx(free.bearing, abs=math.radians(0.01))


def test_a_body_leaving_the_room_stops_the_step_with_time_body_and_place():
    from components.acoustics.room import LeftRoomError

    core = LocalizerCore(room=True, rt60=0.3)
    room_run(core, 12)
    kept = snapshot(core)
    with pytest.raises(LeftRoomError) as caught:
        core.step(0.12, 0.01, 0.2, 6.6, True, **POSE)
    assert str(caught.value) == ("at t = 0.12 s the source is at (0.2, 6.6, 0.3) m, outside the "
                                 "room (x in [-3.5, 3.5], y in [-0.5, 6.5], z in [0, 2.7] m)")
    assert snapshot(core) == kept
    with pytest.raises(LeftRoomError, match=r"the robot's microphone M1 is at \(-3\.6, "):
        core.step(0.12, 0.01, 0.0, 3.0, True, robot_x=-3.2, robot_y=1.0,
                  robot_heading=math.pi / 2)


def test_room_state_round_trip_through_json_repeats_the_future():
    core = LocalizerCore(seed=9, room=True, rt60=0.3, reverb_cut_db=20.0)
    room_run(core, 37)
    saved = json.loads(json.dumps(snapshot(core)))
    assert "lattice" not in json.dumps(saved)            # rebuilt from the parameters
    assert len(saved["__object__"]["history"]["__object__"]["samples"]) > 10
    room_run(core, 40, t0=0.37)
    first = snapshot(core)
    restore(core, saved)
    room_run(core, 40, t0=0.37)
    assert snapshot(core) == first
    assert core.measurement_id >= 6


def test_faults_compose_with_the_room():
    from components.common.faults import Fault, encode_schedule

    def attempt(faults):
        core = LocalizerCore(seed=2, room=True, rt60=0.3, reverb_cut_db=20.0,
                             fault_schedule=encode_schedule(faults))
        room_run(core, 11)
        return core

    plain = attempt([])
    assert plain.fix_status == FixStatus.OK
    assert attempt([Fault("mic_dead", 0.0, channel="M2")]).fix_status == \
        FixStatus.DEAD_MICROPHONE
    # A reflecting wall 0.3 m to the robot's right adds its image to the room's response:
    # the same noise draws, another fix.
    walled = attempt([Fault("reflecting_wall", 0.0, magnitude=0.3)])
    assert walled.faults_active == 1
    assert (walled.tdoa_12, walled.tdoa_23) != (plain.tdoa_12, plain.tdoa_23)
    assert attempt([Fault("low_snr", 0.0, magnitude=-20.0)]).peak_quality < plain.peak_quality

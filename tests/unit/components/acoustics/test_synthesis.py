"""Independent check: microphone signals simulated by pyroomacoustics, fed to the estimator."""

import math

import numpy as np
import pytest

pra = pytest.importorskip("pyroomacoustics")

from components.acoustics import LocalizerSettings, locate_records, make_estimator  # noqa: E402

FS = 100_000  # pyroomacoustics needs an integer rate
ROOM = [7.0, 7.0, 3.0]          # the paper's 7 m x 7 m test area
HEIGHT = 0.25                   # microphones and speaker on small robots
CENTRE = np.array([3.5, 2.0])   # array centre M2; the robot faces +y, so "left" is -x


def room_records(settings, distance, bearing, rt60=None):
    """Records (3, n) from a pyroomacoustics shoebox, cut as the ADC would around the burst."""
    pra.constants.set("c", settings.speed_of_sound)
    if rt60 is None:
        room = pra.ShoeBox(ROOM, fs=FS, max_order=0, air_absorption=False)
    else:
        absorption, order = pra.inverse_sabine(rt60, ROOM)
        room = pra.ShoeBox(ROOM, fs=FS, materials=pra.Material(absorption), max_order=order)
    source = CENTRE + distance * np.array([-math.sin(bearing), math.cos(bearing)])
    burst = settings.burst.waveform(np.arange(int(settings.burst_duration * FS) + 1) / FS)
    room.add_source([source[0], source[1], HEIGHT], signal=np.concatenate([burst, np.zeros(64)]))
    mics = np.array([[CENTRE[0] - 0.4, CENTRE[1], HEIGHT], [CENTRE[0], CENTRE[1], HEIGHT],
                     [CENTRE[0] + 0.4, CENTRE[1], HEIGHT]]).T
    room.add_microphone_array(pra.MicrophoneArray(mics, FS))
    room.simulate()
    signals = room.mic_array.signals
    signals = 0.4 * signals / np.abs(signals).max()
    # pyroomacoustics delays by its fractional-delay filter's half length (common to all mics).
    lead = pra.constants.get("frac_delay_length") // 2
    first = int(np.floor(np.min(np.hypot(*(mics[:2].T - source).T)) / settings.speed_of_sound * FS))
    padded = np.concatenate([np.zeros((3, 200)), signals], axis=1)
    start = 200 + first + lead - int(settings.pre_roll * FS)
    records = padded[:, start:start + settings.record_samples]
    noise = 1e-3 * np.random.default_rng(0).standard_normal(records.shape)
    return records + noise


@pytest.mark.parametrize("bearing_deg", [0.0, 30.0, -45.0, 60.0],
                         ids=["broadside", "left30", "right45", "left60"])
def test_anechoic_room_bearing_within_one_degree_at_2m(bearing_deg):
    settings = LocalizerSettings()
    records = room_records(settings, 2.0, math.radians(bearing_deg))
    fixes = locate_records(settings, make_estimator("exact", 0.4, 340.0), records[None])
    assert bool(fixes.valid[0])
    assert abs(math.degrees(fixes.bearing[0]) - bearing_deg) <= 1.0
    # Range hinges on ~0.02-sample delay sums; pyroomacoustics' own 81-tap fractional delay
    # filter limits the agreement to a few centimetres.
    assert fixes.distance[0] == pytest.approx(2.0, abs=0.05)

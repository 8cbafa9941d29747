"""The localizer's room parameters: what is refused before t0, with the field and valid range."""

import math

import pytest

from components.acoustics import LocalizerSettings
from components.acoustics.room import eyring_rt60, image_absorption
from components.acoustics.settings import DEFAULTS, MAX_IMAGES
from components.common.errors import ParameterError


def refusal(**parameters):
    with pytest.raises(ParameterError) as caught:
        LocalizerSettings(room=True, **parameters)
    message = str(caught.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("name", ["mic_height", "source_height"])
def test_a_body_above_the_ceiling_is_refused(name):
    message = refusal(**{name: 2.8})
    assert f"{name} = 2.8 m puts" in message and "valid (0, room_height = 2.7) m" in message


def test_an_array_wider_than_the_room_is_refused():
    assert "mic_spacing = 0.4 m: the array (2 x spacing) does not fit in a 0.7 x 7.0 m room" \
        in refusal(room_length_x=0.7)


@pytest.mark.parametrize("name", ["absorption_walls", "absorption_floor", "absorption_ceiling"])
@pytest.mark.parametrize("value", [-0.1, 1.5])
def test_absorption_outside_zero_one_is_refused(name, value):
    assert f"{name} = {value!r} must be in [0, 1]" in refusal(**{name: value})


def test_an_rt60_no_room_of_that_size_has_is_refused():
    # 0.03 s in the 7 x 7 x 2.7 m lab needs more than the 0.99 absorption of anechoic wedges.
    assert image_absorption(0.03, (7.0, 7.0, 2.7), 340.0) > 0.99
    message = refusal(rt60=0.03)
    assert message.startswith("AcousticLocalizer: rt60 = 0.03 s: no 7 x 7 x 2.7 m room has it")
    assert "valid for this room: [0.0366, 16.7] s" in message
    # A smaller room, whose sound meets its walls more often, can have it.
    LocalizerSettings(room=True, rt60=0.03, room_length_x=3.0, room_length_y=3.0,
                      room_height=2.0)


def test_an_rt60_beyond_what_the_localizer_computes_names_the_longest():
    message = refusal(rt60=3.0)
    assert f"more than the {MAX_IMAGES} the localizer computes" in message
    assert "valid RT60 for this room at this cut: [0.0366, 1.07] s" in message
    LocalizerSettings(room=True, rt60=1.0)


def test_hard_walls_never_stop_ringing():
    message = refusal(absorption_walls=0.0, absorption_floor=0.0, absorption_ceiling=0.0)
    assert "(RT60 inf s)" in message


def test_rt60_sets_one_absorption_and_the_time_cut():
    settings = LocalizerSettings(room=True, rt60=0.4, reverb_cut_db=30.0)
    alpha = image_absorption(0.4, (7.0, 7.0, 2.7), 340.0)
    assert settings.room_absorption == (alpha, alpha, alpha)
    assert settings.room_rt60 == pytest.approx(0.4, rel=1e-9)
    assert settings.room_time_cut == pytest.approx(0.2, rel=1e-9)
    # Eyring's formula for the same absorption: 36 % shorter (the image decay is not diffuse).
    assert eyring_rt60((7.0, 7.0, 2.7), alpha, alpha, alpha, 340.0) == pytest.approx(
        0.4 / 1.36, rel=0.01)


def test_room_relations_are_not_checked_in_free_field():
    settings = LocalizerSettings(room=False, mic_height=9.0, rt60=0.001)
    assert settings.room_absorption is None
    assert settings.as_dict()["mic_height"] == 9.0


def test_every_room_parameter_has_a_default():
    names = ("room", "room_origin_x", "room_origin_y", "room_length_x", "room_length_y",
             "room_height", "absorption_walls", "absorption_floor", "absorption_ceiling",
             "rt60", "source_height", "mic_height", "reverb_cut_db", "image_order",
             "burst_period")
    assert set(names) <= set(DEFAULTS)
    assert DEFAULTS["room"] is False
    assert math.isfinite(LocalizerSettings(room=True).room_rt60)

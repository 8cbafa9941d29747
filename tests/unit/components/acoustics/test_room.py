"""The shoebox room: image sources against exact geometry and pyroomacoustics, RT60 formulas."""

import doctest
import math

import numpy as np
import pytest

from components.acoustics import room as room_module
from components.acoustics.room import (ImageLattice, LeftRoomError, ShoeboxRoom, eyring_rt60,
                                       image_absorption, image_rt60, sabine_rt60)

SIZE = (7.0, 6.0, 2.7)


def test_the_module_examples_hold():
    assert doctest.testmod(room_module).failed == 0


def _find(images, point):
    """Row of the image at ``point`` (exact coordinates), or None."""
    hits = np.flatnonzero(np.all(np.abs(images - np.asarray(point)[:, None]) < 1e-12, axis=0))
    return int(hits[0]) if hits.size else None


def test_one_wall_gives_the_mirror_image_only():
    # Only the floor reflects (walls and ceiling absorb everything): the direct path and the
    # floor's mirror image, nothing else with a non-zero amplitude.
    room = ShoeboxRoom((0.0, 0.0), SIZE, 1.0, 0.19, 1.0)
    lattice = ImageLattice(room, 40.0)
    source = np.array([2.0, 3.5, 0.3])
    images = lattice.images(source)
    audible = np.flatnonzero(lattice.attenuation > 0.0)
    assert {_find(images, source), _find(images, (2.0, 3.5, -0.3))} == set(audible.tolist())
    floor = _find(images, (2.0, 3.5, -0.3))
    assert lattice.order[floor] == 1
    assert lattice.attenuation[floor] == pytest.approx(math.sqrt(1.0 - 0.19), rel=1e-15)


def test_a_corner_gives_its_three_images_with_their_reflections():
    # The corner of the wall x = 0 and the floor: images across the wall, the floor, and both.
    beta_wall, beta_floor = 0.8, 0.9
    room = ShoeboxRoom((0.0, 0.0), SIZE, 1.0 - beta_wall**2, 1.0 - beta_floor**2, 0.5)
    lattice = ImageLattice(room, 40.0, max_order=2)
    x, y, z = 0.7, 2.2, 0.4
    images = lattice.images((x, y, z))
    expected = {(-x, y, z): (1, beta_wall), (x, y, -z): (1, beta_floor),
                (-x, y, -z): (2, beta_wall * beta_floor)}
    for point, (order, attenuation) in expected.items():
        row = _find(images, point)
        assert row is not None, point
        assert lattice.order[row] == order
        assert lattice.attenuation[row] == pytest.approx(attenuation, rel=1e-14)
    # Order <= 2 in a shoebox: 1 + 6 + 18 images (the octahedral numbers).
    assert len(lattice) == 25


def test_lattice_covers_every_image_within_its_path_and_no_more_than_needed():
    room = ShoeboxRoom((0.0, 0.0), SIZE, 0.3, 0.3, 0.3)
    max_path = 30.0
    lattice = ImageLattice(room, max_path)
    point, listener = np.array([1.1, 4.9, 0.3]), np.array([5.5, 0.7, 1.9])
    # Brute force over a generous index range: every image within max_path is in the lattice.
    j = np.stack(np.meshgrid(np.arange(-4, 5), np.arange(-4, 5), np.arange(-8, 9),
                             indexing="ij"), axis=-1).reshape(-1, 3)
    ours = {tuple(np.round(p, 9)) for p in lattice.images(point).T}
    within = 0
    for q in np.ndindex(2, 2, 2):
        candidates = (1 - 2 * np.array(q)) * point + 2 * j * np.array(SIZE)
        near = candidates[np.linalg.norm(candidates - listener, axis=1) <= max_path]
        within += len(near)
        assert {tuple(np.round(p, 9)) for p in near} <= ours
    distances = np.linalg.norm(lattice.images(point) - listener[:, None], axis=0)
    assert within == np.count_nonzero(distances <= max_path)


def test_images_delays_and_amplitudes_equal_pyroomacoustics():
    pra = pytest.importorskip("pyroomacoustics")
    absorption = {"walls": 0.3, "floor": 0.1, "ceiling": 0.6}
    materials = {wall: pra.Material(absorption["walls"])
                 for wall in ("east", "west", "north", "south")}
    materials.update(floor=pra.Material(absorption["floor"]),
                     ceiling=pra.Material(absorption["ceiling"]))
    order = 4
    room = pra.ShoeBox(list(SIZE), fs=100_000, materials=materials, max_order=order,
                       air_absorption=False)
    source, mic = [2.0, 3.1, 0.3], [3.0, 1.0, 0.2]
    room.add_source(source)
    room.add_microphone(mic)
    room.image_source_model()
    theirs = room.sources[0]
    ours = ImageLattice(ShoeboxRoom((0.0, 0.0), SIZE, absorption["walls"],
                                    absorption["floor"], absorption["ceiling"]),
                        100.0, max_order=order)
    images = ours.images(source)
    assert len(ours) == theirs.images.shape[1] == 129
    # Pair each of theirs with our nearest image (theirs are float32).
    gap = np.linalg.norm(theirs.images.astype(float)[:, :, None] - images[:, None, :], axis=0)
    match = gap.argmin(axis=1)
    assert np.unique(match).size == len(ours)
    assert gap.min(axis=1).max() < 2e-6
    c = 343.0
    their_distance = np.linalg.norm(theirs.images.astype(float) - np.c_[mic], axis=0)
    our_distance = np.linalg.norm(images[:, match] - np.c_[mic], axis=0)
    np.testing.assert_allclose(our_distance / c, their_distance / c, rtol=1e-6)
    # Amplitudes: pyroomacoustics' damping / distance, ours attenuation / distance.
    np.testing.assert_allclose(ours.attenuation[match] / our_distance,
                               theirs.damping[0] / their_distance, rtol=1e-6)
    np.testing.assert_array_equal(ours.order[match], theirs.orders)


def test_reverberation_time_formulas():
    # Sabine and Eyring agree for small absorption and part ways as it grows.
    assert sabine_rt60(SIZE, 0.01, 0.01, 0.01, 340.0) == pytest.approx(
        eyring_rt60(SIZE, 0.01, 0.01, 0.01, 340.0), rel=0.01)
    volume, surface = SIZE[0] * SIZE[1] * SIZE[2], 2 * (7 * 6 + 7 * 2.7 + 6 * 2.7)
    assert eyring_rt60(SIZE, 0.3, 0.3, 0.3, 340.0) == pytest.approx(
        24.0 * math.log(10.0) * volume / (340.0 * surface * -math.log(0.7)), rel=1e-12)
    # The image sources' decay inverts exactly and scales as 1 / -ln(1 - alpha).
    for rt60 in (0.2, 0.5, 1.0):
        alpha = image_absorption(rt60, SIZE, 340.0)
        assert image_rt60(SIZE, alpha, alpha, alpha, 340.0) == pytest.approx(rt60, rel=1e-9)
    assert image_rt60(SIZE, 1.0, 1.0, 1.0, 340.0) == 0.0
    assert image_rt60(SIZE, 0.0, 0.0, 0.0, 340.0) == math.inf


def test_image_decay_against_a_brute_force_sum_over_images():
    # The direction integral of image_rt60 against the energy of the lattice's own images
    # (1/r^2 times the reflections), averaged over placements, read the same way (T20).
    size, alpha = (7.0, 7.0, 2.7), 0.34
    room = ShoeboxRoom((0.0, 0.0), size, alpha, alpha, alpha)
    lattice = ImageLattice(room, 340.0 * 0.35)
    rng = np.random.default_rng(5)
    measured = []
    for _ in range(8):
        source = rng.uniform((0.5, 0.5, 0.3), (6.5, 6.5, 2.4))
        listener = rng.uniform((0.5, 0.5, 0.3), (6.5, 6.5, 2.4))
        distance = np.linalg.norm(lattice.images(source) - listener[:, None], axis=0)
        order = np.argsort(distance)
        times, energy = distance[order] / 340.0, (lattice.attenuation[order] / distance[order])**2
        decay = np.cumsum(energy[::-1])[::-1]
        level = 10.0 * np.log10(decay / decay[0])
        fit = (level <= -5.0) & (level >= -25.0)
        grid = np.linspace(times[fit][0], times[fit][-1], 400)
        slope = np.polyfit(grid, np.interp(grid, times, level), 1)[0]
        measured.append(-60.0 / slope)
    assert np.mean(measured) == pytest.approx(image_rt60(size, alpha, alpha, alpha, 340.0),
                                              rel=0.03)


def test_leaving_the_room_names_time_body_and_place():
    room = ShoeboxRoom((-3.5, -0.5), (7.0, 7.0, 2.7), 0.3, 0.3, 0.3)
    room.check_inside("the source", (0.0, 6.4, 0.3), 1.0)
    with pytest.raises(LeftRoomError) as caught:
        room.check_inside("the source", (0.1, 6.52, 0.3), 12.34)
    assert str(caught.value) == ("at t = 12.34 s the source is at (0.1, 6.52, 0.3) m, outside "
                                 "the room (x in [-3.5, 3.5], y in [-0.5, 6.5], z in [0, 2.7] m)")

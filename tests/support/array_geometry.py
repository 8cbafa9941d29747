"""The exact geometry of an imperfect three-microphone array, written apart from the code.

Reference for the localizer's microphone offsets and ADC channel skews: the true microphone
positions from the robot's pose, the delays a source gives them (as skewed channels sample
them), and the fix the *nominal* array's equations give for those delays, solved numerically
(scipy) rather than by the estimator's closed form.
"""

import math

import numpy as np
from scipy.optimize import root

__all__ = ["SPACING", "SOUND", "true_microphones", "source_at", "skewed_tdoas", "nominal_fix",
           "fix_tolerance"]

SPACING, SOUND = 0.4, 340.0


def true_microphones(pose, offsets=((0.0, 0.0),) * 3, spacing=SPACING):
    """World (x, y) of M1, M2, M3: nominal ``+l, 0, -l`` to the left, plus ``(along, across)``."""
    x, y, heading = pose
    forward = np.array([math.cos(heading), math.sin(heading)])
    left = np.array([-math.sin(heading), math.cos(heading)])
    return np.array([np.array([x, y]) + (nominal + along) * left + across * forward
                     for nominal, (along, across) in zip((spacing, 0.0, -spacing), offsets)])


def source_at(pose, distance, bearing):
    """World (x, y) of a source ``distance`` from the robot point at ``bearing`` (left +)."""
    x, y, heading = pose
    return np.array([x + distance * math.cos(heading + bearing),
                     y + distance * math.sin(heading + bearing)])


def skewed_tdoas(source, microphones, skews=(0.0, 0.0, 0.0)):
    """``(tdoa_12, tdoa_23)`` as the channels record them: channel i sampled ``skew_i`` late
    sees its arrival ``skew_i`` early."""
    heard = [math.dist(source, mic) / SOUND - skew for mic, skew in zip(microphones, skews)]
    return heard[0] - heard[1], heard[2] - heard[1]


def nominal_fix(tdoa_12, tdoa_23, guess=(2.0, 0.0), spacing=SPACING):
    """``(distance, bearing)`` from M2 of the nominal array that explains the delays exactly.

    The nominal array in its own frame: M1 at ``+l`` to the left, M2 at 0, M3 at ``-l``; a
    source ``D`` away at bearing ``b`` sits at ``(D cos b, D sin b)`` (forward, left).
    """
    def residual(unknowns):
        distance, bearing = unknowns
        forward, left = distance * math.cos(bearing), distance * math.sin(bearing)
        ranges = [math.hypot(forward, left - side) for side in (spacing, 0.0, -spacing)]
        # In metres of path: seconds would leave the solver's tolerances meaningless.
        return [ranges[0] - ranges[1] - SOUND * tdoa_12, ranges[2] - ranges[1] - SOUND * tdoa_23]

    solution = root(residual, guess, method="hybr", options={"xtol": 1e-14})
    # Solved when the paths agree to 1e-12 m (3e-15 s: a millionth of the tests' tolerances),
    # whether or not the solver could still move in the last bits.
    assert max(map(abs, residual(solution.x))) < 1e-12, solution.message
    return float(solution.x[0]), float(solution.x[1])


def fix_tolerance(tdoa_12, tdoa_23, tdoa_tolerance, guess=(2.0, 0.0)):
    """How far ``(distance, bearing)`` may move when each delay moves by ``tdoa_tolerance``.

    The sum of the two delays' effects (first order, by differences of :func:`nominal_fix`).
    """
    centre = np.array(nominal_fix(tdoa_12, tdoa_23, guess))
    moved = [np.array(nominal_fix(tdoa_12 + dt_12, tdoa_23 + dt_23, guess))
             for dt_12, dt_23 in ((tdoa_tolerance, 0.0), (0.0, tdoa_tolerance))]
    return tuple(sum(abs(m - centre) for m in moved))

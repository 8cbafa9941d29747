"""Membership functions of the FGS-PD fuzzy system.

Inputs: seven triangular sets NB..PB evenly spaced on the normalised universe [-1, 1] (peaks at
-1, -2/3, ..., 1, feet at the neighbouring peaks; NB and PB are shoulders), so at any input
exactly two neighbouring sets are non-zero and their memberships sum to one.

Outputs: two sets on [0, 1], ``Small`` = triangle (0, 0, 1) and ``Big`` = triangle (0, 1, 1),
the Small/Big pair of Zhao, Tomizuka and Isaka (1993). The paper names only the labels; it
does not draw the output sets.
"""

__all__ = [
    "INPUT_TERMS",
    "OUTPUT_TERMS",
    "fuzzify",
    "input_membership",
    "output_membership",
]

INPUT_TERMS = ("NB", "NM", "NS", "Z", "PS", "PM", "PB")
OUTPUT_TERMS = ("S", "B")

_LAST_GAP = len(INPUT_TERMS) - 2  # index of the last pair of neighbouring sets
_SCALE = (len(INPUT_TERMS) - 1) / 2.0  # peaks per unit of the normalised universe


def fuzzify(x):
    """Fuzzify a normalised input on the seven triangular sets.

    Parameters
    ----------
    x : float
        Normalised input; values outside [-1, 1] are clipped (NB and PB are shoulders).

    Returns
    -------
    index : int
        Index ``i`` in :data:`INPUT_TERMS` of the left one of the two active sets.
    mu_left : float
        Membership of set ``i``.
    mu_right : float
        Membership of set ``i + 1``; ``mu_left + mu_right == 1``.
    """
    if x <= -1.0:
        return 0, 1.0, 0.0
    if x >= 1.0:
        return _LAST_GAP, 0.0, 1.0
    position = (x + 1.0) * _SCALE
    index = int(position)
    if index > _LAST_GAP:
        index = _LAST_GAP
    fraction = position - index
    return index, 1.0 - fraction, fraction


def input_membership(x, term):
    """Membership of a normalised input in one input set.

    Parameters
    ----------
    x : float
        Normalised input (clipped to [-1, 1]).
    term : str
        One of :data:`INPUT_TERMS`.

    Returns
    -------
    float
        Membership degree in [0, 1].
    """
    k = INPUT_TERMS.index(term)
    index, mu_left, mu_right = fuzzify(x)
    if k == index:
        return mu_left
    if k == index + 1:
        return mu_right
    return 0.0


def output_membership(y, term):
    """Membership of a normalised gain ``y`` in [0, 1] in the output set Small or Big.

    Parameters
    ----------
    y : float
        Normalised gain.
    term : str
        ``"S"`` (Small, triangle (0, 0, 1)) or ``"B"`` (Big, triangle (0, 1, 1)).

    Returns
    -------
    float
        Membership degree in [0, 1]; zero outside [0, 1].
    """
    if not 0.0 <= y <= 1.0:
        return 0.0
    if term == "S":
        return 1.0 - y
    if term == "B":
        return y
    raise KeyError(f"output term {term!r} is not one of {OUTPUT_TERMS}")

"""The fuzzy inference engine that maps (error, error rate) to normalised gains Kp', Kd'.

Mamdani max-min inference over the 7x7 rule tables, then either the centre of gravity of the
aggregated output set (``method="mamdani"``) or the weighted average of the paper's
Eqs. (51)-(52) (``method="weighted"``, the default; see :class:`FuzzyGainScheduler`).

Because the input sets are a triangular partition, at most 2 x 2 rules fire, and the centroid
has a closed form (:func:`.defuzzify.exact_centroid`), so one evaluation is a few microseconds
of plain Python, with no numpy call on the hot path.
"""

import numpy as np

from ..common.errors import ParameterError
from .defuzzify import discrete_centroid, exact_centroid
from .membership import fuzzify
from .rules import KD_TABLE, KP_TABLE, rule_matrix

__all__ = ["FuzzyGainScheduler", "METHODS", "CENTROIDS"]

METHODS = ("weighted", "mamdani")
CENTROIDS = ("exact", "discrete")


class FuzzyGainScheduler:
    """Fuzzy system of the FGS-PD controller: (e, de) -> (Kp', Kd') in [0, 1].

    Parameters
    ----------
    e_range : float
        Error that maps to the edge of the normalised universe [-1, 1] [m/s]; larger errors
        saturate (NB / PB).
    de_range : float
        Error rate that maps to the edge of the universe [m/s^2].
    method : {"weighted", "mamdani"}
        ``"weighted"`` (default): Eqs. (51)-(52), ``sum(w_i C_i) / sum(w_i)`` with rule
        strength ``w_i = min(mu_e, mu_de)`` and ``C_i`` = 0 (Small) or 1 (Big). It is what the
        paper prints, and it spans the whole range [0, 1], so Eq. (50) reaches kp_min..kp_max.
        ``"mamdani"``: max-min aggregation and centre of gravity of the clipped output sets;
        with Small = (0, 0, 1) and Big = (0, 1, 1) its value only spans [1/3, 2/3], the middle
        third of each gain range.
    centroid : {"exact", "discrete"}
        For ``"mamdani"``: the closed-form centroid (default), or scikit-fuzzy's sampled one on
        ``universe_points`` points of [0, 1] (numpy; for comparison with scikit-fuzzy).
    universe_points : int
        Samples of the output universe for ``centroid="discrete"``.
    kp_table, kd_table : sequence of str
        Rule tables (rows e = NB..PB, columns de = NB..PB); default those of :mod:`components.control.rules`.

    Raises
    ------
    ParameterError
        On a non-positive range, an unknown method or centroid, or a malformed table.
    """

    def __init__(self, e_range, de_range, method="weighted", centroid="exact",
                 universe_points=101, kp_table=KP_TABLE, kd_table=KD_TABLE):
        for name, value in (("e_range", e_range), ("de_range", de_range)):
            if not (np.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} = {value!r} must be a positive finite number")
        if method not in METHODS:
            raise ParameterError(f"method = {method!r} is not one of {METHODS}")
        if centroid not in CENTROIDS:
            raise ParameterError(f"centroid = {centroid!r} is not one of {CENTROIDS}")
        if int(universe_points) < 3:
            raise ParameterError(f"universe_points = {universe_points!r} must be at least 3")
        self.e_range = float(e_range)
        self.de_range = float(de_range)
        self.method = method
        self.centroid = centroid
        self.universe = np.linspace(0.0, 1.0, int(universe_points))
        self.kp_rules = rule_matrix(kp_table)
        self.kd_rules = rule_matrix(kd_table)

    def evaluate(self, e, de):
        """Normalised gains for an error and its rate in physical units.

        Parameters
        ----------
        e : float
            Speed error [m/s].
        de : float
            Error rate [m/s^2].

        Returns
        -------
        kp_n, kd_n : float
            Kp' and Kd' in [0, 1].
        """
        return self.evaluate_normalised(e / self.e_range, de / self.de_range)

    def evaluate_normalised(self, e_n, de_n):
        """Normalised gains for inputs already on the universe [-1, 1] (clipped beyond).

        Parameters
        ----------
        e_n, de_n : float
            Normalised error and error rate.

        Returns
        -------
        kp_n, kd_n : float
            Kp' and Kd' in [0, 1].
        """
        i, a0, a1 = fuzzify(e_n)
        j, b0, b1 = fuzzify(de_n)
        w00 = a0 if a0 < b0 else b0
        w01 = a0 if a0 < b1 else b1
        w10 = a1 if a1 < b0 else b0
        w11 = a1 if a1 < b1 else b1
        if self.method == "weighted":
            # sum(w_i C_i) / sum(w_i) over the four firing rules, for both tables; written out
            # rather than in a helper called twice, because this runs every control step.
            total = w00 + w01 + w10 + w11
            kp_row, kp_next_row = self.kp_rules[i], self.kp_rules[i + 1]
            kd_row, kd_next_row = self.kd_rules[i], self.kd_rules[i + 1]
            return ((w00 * kp_row[j] + w01 * kp_row[j + 1]
                     + w10 * kp_next_row[j] + w11 * kp_next_row[j + 1]) / total,
                    (w00 * kd_row[j] + w01 * kd_row[j + 1]
                     + w10 * kd_next_row[j] + w11 * kd_next_row[j + 1]) / total)
        return (self._mamdani(self.kp_rules, i, j, w00, w01, w10, w11),
                self._mamdani(self.kd_rules, i, j, w00, w01, w10, w11))

    def _mamdani(self, rules, i, j, w00, w01, w10, w11):
        row, next_row = rules[i], rules[i + 1]
        strength = [0.0, 0.0]  # max firing of Small, of Big
        for weight, big in ((w00, row[j]), (w01, row[j + 1]),
                            (w10, next_row[j]), (w11, next_row[j + 1])):
            if weight > strength[big]:
                strength[big] = weight
        if self.centroid == "exact":
            return exact_centroid(strength[0], strength[1])
        return discrete_centroid(strength[0], strength[1], self.universe)

"""The 7x7 rule tables for the normalised gains Kp' and Kd'.

The paper's Tables 4 and 5 are garbled in print (shifted columns); these are the tables of
Zhao, Tomizuka and Isaka (IEEE SMC 1993) (docs/errata.md). Rows are e = NB..PB, columns
de = NB..PB; ``B`` is the output set Big, ``S`` Small.
"""

from ..common.errors import ParameterError
from .membership import INPUT_TERMS, OUTPUT_TERMS

__all__ = ["KP_TABLE", "KD_TABLE", "rule_matrix", "BIG", "SMALL"]

SMALL = 0
BIG = 1

KP_TABLE = ("BBBBBBB", "SBBBBBS", "SSBBBSS", "SSSBSSS", "SSBBBSS", "SBBBBBS", "BBBBBBB")
KD_TABLE = ("SSSSSSS", "BBSSSBB", "BBBSBBB", "BBBBBBB", "BBBSBBB", "BBSSSBB", "SSSSSSS")


def rule_matrix(table):
    """Turn a rule table of ``S``/``B`` strings into a tuple of 0/1 rows.

    Parameters
    ----------
    table : sequence of str
        Seven strings of seven characters, rows e = NB..PB, columns de = NB..PB.

    Returns
    -------
    tuple of tuple of int
        ``matrix[i][j]`` is :data:`BIG` (1) or :data:`SMALL` (0) for e set ``i``, de set ``j``.

    Raises
    ------
    ParameterError
        If the table is not 7x7 or holds a letter other than S and B.
    """
    n = len(INPUT_TERMS)
    if len(table) != n or any(len(row) != n for row in table):
        raise ParameterError(f"rule table must be {n} rows of {n} letters, got {list(table)!r}")
    matrix = []
    for i, row in enumerate(table):
        bad = [c for c in row if c not in OUTPUT_TERMS]
        if bad:
            raise ParameterError(
                f"rule table row e={INPUT_TERMS[i]} = {row!r}: letters {bad} are not one of "
                f"{OUTPUT_TERMS}")
        matrix.append(tuple(BIG if c == "B" else SMALL for c in row))
    return tuple(matrix)

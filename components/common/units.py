"""The units a sonotrack port may carry, as SI base-unit exponents (FMI 2.0 ``BaseUnit``).

Kept apart from the slave base so that the port tables (:mod:`.ranges`) can refuse an unknown
unit without importing pythonfmu.
"""

__all__ = ["UNIT_BASES"]

UNIT_BASES = {
    "1": {},
    "m": {"m": 1},
    "m2": {"m": 2},
    "s": {"s": 1},
    "Hz": {"s": -1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "1/m": {"m": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "V": {"kg": 1, "m": 2, "s": -3, "A": -1},
    "A": {"A": 1},
    "Ohm": {"kg": 1, "m": 2, "s": -3, "A": -2},
    "H": {"kg": 1, "m": 2, "s": -2, "A": -2},
    "N.m/A": {"kg": 1, "m": 2, "s": -2, "A": -1},
    "V.s/rad": {"kg": 1, "m": 2, "s": -2, "A": -1, "rad": -1},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "1/V": {"kg": -1, "m": -2, "s": 3, "A": 1},
    "1/(m/s)": {"m": -1, "s": 1},
    "1/(m/s2)": {"m": -1, "s": 2},
    "V/(m/s)": {"kg": 1, "m": 1, "s": -2, "A": -1},
    "V.s/m": {"kg": 1, "m": 1, "s": -2, "A": -1},
    "V.s2/m": {"kg": 1, "m": 1, "s": -1, "A": -1},
    "V/m": {"kg": 1, "m": 1, "s": -3, "A": -1},
    "dB": {},
    "deg": {"rad": 1},
}

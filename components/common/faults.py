"""Fault schedules as data: what goes wrong, where, when and how badly.

A schedule is a list of :class:`Fault` entries. A scenario's ``[[faults]]`` section is checked
by :func:`check_entry` (the orchestrator, before any FMU loads) and turned into one compact JSON
string per targeted instance by :func:`encode_schedule`; the FMU receives it as its String
parameter ``fault_schedule`` and parses it with :func:`parse_schedule` -- the same checks, so
a host other than ours (libcosim, a C host) that sets a bad schedule gets the same message.
Each FMU then applies its own schedule in ``do_step``: a fault behaves the same in any host.

An entry is active on ``start <= t < end`` (``end`` absent or null: permanent).

Examples
--------
>>> text = encode_schedule([Fault("mic_dead", 2.0, 4.0, channel="M2")])
>>> text
'[{"kind":"mic_dead","start":2.0,"end":4.0,"magnitude":0.0,"channel":"M2"}]'
>>> schedule = parse_schedule(text, "AcousticLocalizer")
>>> [fault.kind for fault in schedule.active(3.0)]
['mic_dead']
"""

import json
import math
from dataclasses import dataclass

from .errors import ParameterError

__all__ = ["FaultKind", "KINDS", "Fault", "FaultSchedule", "check_entry", "parse_schedule",
           "encode_schedule", "kinds_of", "MICROPHONES", "WHEELS", "REFLECTION_COEFFICIENT",
           "IMPULSES_PER_RECORD"]

MICROPHONES = ("M1", "M2", "M3")
WHEELS = ("left", "right", "both")
# A hard, smooth wall (concrete, glass) reflects about 0.9 of the amplitude at these frequencies.
REFLECTION_COEFFICIENT = 0.9
# Clicks (a relay, a dropped tool) per microphone record while impulsive noise is active.
IMPULSES_PER_RECORD = 3


@dataclass(frozen=True)
class FaultKind:
    """What one fault kind means and which values it takes.

    Attributes
    ----------
    model : str
        FMU model that applies it.
    magnitude : str
        What ``magnitude`` is, with its unit.
    low, high : float
        Valid magnitude range (inclusive).
    default : float
        Magnitude when none is given.
    channels : tuple of str
        Valid ``channel`` values (empty: the kind takes no channel).
    region : bool
        Whether the kind needs a floor ``region`` [x_min, y_min, x_max, y_max].
    """

    model: str
    magnitude: str
    low: float
    high: float
    default: float
    channels: tuple = ()
    region: bool = False


KINDS = {
    "mic_dead": FaultKind("AcousticLocalizer", "unused", 0.0, 0.0, 0.0, MICROPHONES),
    "mic_clipping": FaultKind("AcousticLocalizer", "clip level, fraction of the ADC full "
                              "scale", 0.001, 1.0, 0.05, MICROPHONES),
    "mic_gain": FaultKind("AcousticLocalizer", "gain factor of the channel", 0.0, 100.0, 0.5,
                          MICROPHONES),
    "impulsive_noise": FaultKind("AcousticLocalizer", "click peak, fraction of the ADC full "
                                 "scale", 0.0, 1.0, 0.8),
    "low_snr": FaultKind("AcousticLocalizer", "SNR at 1 m in dB while active", -30.0, 60.0, 0.0),
    "lost_fixes": FaultKind("AcousticLocalizer", "fraction of fix attempts dropped (0.5: "
                            "every other)", 0.0, 1.0, 0.5),
    "reflecting_wall": FaultKind("AcousticLocalizer", "x of a wall parallel to the y axis, m "
                                 "(image source, reflection 0.9)", -50.0, 50.0, 1.0),
    "source_silent": FaultKind("SoundSource", "unused", 0.0, 0.0, 0.0),
    "encoder_skip": FaultKind("RobotPlant", "fraction of counts lost", 0.0, 1.0, 0.5, WHEELS),
    "encoder_freeze": FaultKind("RobotPlant", "unused", 0.0, 0.0, 0.0, WHEELS),
    "low_friction": FaultKind("RobotPlant", "friction coefficient mu on the patch", 0.001, 2.0,
                              0.1, WHEELS, region=True),
    "supply_sag": FaultKind("RobotPlant", "supply voltage while active, V", 0.0, 100.0, 6.0,
                            WHEELS),
    # 0.19 N m: 20 % of RobotPlant's stall torque at the wheel at 11.1 V (docs/faults.md)
    "load_torque": FaultKind("RobotPlant", "torque against the wheel's forward rotation while "
                             "active, N m at the wheel (negative: pushing forward)", -10.0, 10.0,
                             0.19, WHEELS),
}

_FIELDS = ("kind", "target", "start", "end", "magnitude", "channel", "region")


def kinds_of(model):
    """Return the fault kinds that FMU model ``model`` applies, in :data:`KINDS` order."""
    return tuple(name for name, kind in KINDS.items() if kind.model == model)


@dataclass(frozen=True)
class Fault:
    """One scheduled fault.

    Attributes
    ----------
    kind : str
        A key of :data:`KINDS`.
    start, end : float
        Active on ``start <= t < end`` [s]; ``end`` is ``inf`` for a permanent fault.
    magnitude : float
        See :attr:`FaultKind.magnitude`.
    channel : str
        Microphone or wheel it hits ("" when the kind takes none).
    region : tuple of float
        ``(x_min, y_min, x_max, y_max)`` of a floor patch [m] (empty when not used).
    """

    kind: str
    start: float
    end: float = math.inf
    magnitude: float = 0.0
    channel: str = ""
    region: tuple = ()

    def active(self, time):
        """Whether the fault is active at ``time`` [s]."""
        return self.start <= time < self.end

    @property
    def permanent(self):
        """Whether the fault never ends."""
        return math.isinf(self.end)

    def covers(self, x, y):
        """Whether the floor point (x, y) lies in the fault's region (always, if it has none)."""
        if not self.region:
            return True
        x_min, y_min, x_max, y_max = self.region
        return x_min <= x <= x_max and y_min <= y <= y_max

    def hits(self, channel):
        """Whether the fault hits ``channel`` ("both" hits either wheel)."""
        return self.channel == channel or self.channel == "both"

    def to_json(self):
        """Plain dict for :func:`encode_schedule` (no target: the FMU is the target)."""
        data = {"kind": self.kind, "start": self.start,
                "end": None if self.permanent else self.end, "magnitude": self.magnitude}
        if self.channel:
            data["channel"] = self.channel
        if self.region:
            data["region"] = list(self.region)
        return data


class FaultSchedule:
    """The faults one FMU applies; :meth:`active` answers what is on at a time.

    Parameters
    ----------
    faults : sequence of Fault
    """

    def __init__(self, faults=()):
        self.faults = tuple(faults)

    def __bool__(self):
        return bool(self.faults)

    def __len__(self):
        return len(self.faults)

    def active(self, time, kind=None):
        """Return the faults active at ``time`` (of ``kind`` only, if given)."""
        return [f for f in self.faults if f.active(time) and (kind is None or f.kind == kind)]

    def count_active(self, time):
        """Number of faults active at ``time``."""
        return sum(1 for f in self.faults if f.active(time))


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_entry(entry, model=None, targeted=True):
    """Check one schedule entry; return ``(fault, target, problems)``.

    Parameters
    ----------
    entry : dict
        Fields kind, target (when ``targeted``), start, end, magnitude, channel, region.
    model : str, optional
        If given, the kind must be one this FMU model applies.
    targeted : bool
        Whether ``target`` is required (scenario entries) or refused (an FMU's own schedule).

    Returns
    -------
    tuple
        ``(Fault or None, target or None, problems)``; each problem is ``(field, message)``
        naming the bad value and the valid choices.
    """
    problems = []
    allowed = _FIELDS if targeted else tuple(f for f in _FIELDS if f != "target")
    if not isinstance(entry, dict):
        return None, None, [("", f"{entry!r} is not a table of {', '.join(allowed)}")]
    for key in entry:
        if key not in allowed:
            problems.append((key, f"unknown field; valid fields: {', '.join(allowed)}"))
    valid_kinds = kinds_of(model) if model else tuple(KINDS)
    kind_name = entry.get("kind")
    if kind_name not in valid_kinds:
        problems.append(("kind", f"{kind_name!r} is not one of {', '.join(valid_kinds)}"))
        return None, None, problems
    kind = KINDS[kind_name]
    target = entry.get("target")
    if targeted and not (isinstance(target, str) and target):
        problems.append(("target", f"{target!r} is not an instance name (a {kind.model})"))
    start = entry.get("start", 0.0)
    if not (_number(start) and math.isfinite(start) and start >= 0.0):
        problems.append(("start", f"{start!r} is not a finite number of seconds >= 0"))
        start = None
    end = entry.get("end")
    if end is None:
        end = math.inf
    elif not (_number(end) and math.isfinite(end)):
        problems.append(("end", f"{end!r} is not a finite number of seconds (leave it out "
                                "for a permanent fault)"))
        end = None
    elif start is not None and end <= start:
        problems.append(("end", f"{end!r} must be > start = {start!r}"))
    magnitude = entry.get("magnitude", kind.default)
    if not (_number(magnitude) and math.isfinite(magnitude)
            and kind.low <= magnitude <= kind.high):
        problems.append(("magnitude", f"{magnitude!r} is outside {kind.low:g}..{kind.high:g} "
                                      f"({kind.magnitude})"))
    channel = entry.get("channel", "")
    if kind.channels:
        if channel == "" and kind.channels == WHEELS:
            channel = "both"
        if channel not in kind.channels:
            problems.append(("channel", f"{channel!r} is not one of "
                                        f"{', '.join(kind.channels)}"))
    elif channel:
        problems.append(("channel", f"{channel!r}: {kind_name} takes no channel"))
    region = entry.get("region", ())
    if kind.region:
        if not (isinstance(region, (list, tuple)) and len(region) == 4
                and all(_number(v) and math.isfinite(v) for v in region)
                and region[0] < region[2] and region[1] < region[3]):
            problems.append(("region", f"{region!r} is not [x_min, y_min, x_max, y_max] in m "
                                       "with x_min < x_max and y_min < y_max"))
    elif region:
        problems.append(("region", f"{region!r}: {kind_name} takes no region"))
    if problems:
        return None, target, problems
    fault = Fault(kind_name, float(start), float(end), float(magnitude), str(channel),
                  tuple(float(v) for v in region))
    return fault, target, problems


def parse_schedule(text, model):
    """Parse an FMU's ``fault_schedule`` parameter (a JSON list; "" means no faults).

    Parameters
    ----------
    text : str
        As written by :func:`encode_schedule`.
    model : str
        The FMU model name; only its own kinds are accepted.

    Returns
    -------
    FaultSchedule

    Raises
    ------
    ParameterError
        Naming ``fault_schedule``, the entry, the field, the bad value and the valid choices.
    """
    if not text or not text.strip():
        return FaultSchedule()
    try:
        entries = json.loads(text)
    except ValueError as exc:
        raise ParameterError(f"{model}: fault_schedule is not JSON ({exc}); expected a list "
                             "of {kind, start, end, magnitude, channel, region}") from None
    if not isinstance(entries, list):
        raise ParameterError(f"{model}: fault_schedule = {text!r} is not a JSON list")
    faults, problems = [], []
    for index, entry in enumerate(entries):
        fault, _, entry_problems = check_entry(entry, model, targeted=False)
        problems += [f"fault_schedule[{index}].{field}: {message}"
                     for field, message in entry_problems]
        if fault is not None:
            faults.append(fault)
    if problems:
        raise ParameterError(f"{model}: " + "; ".join(problems))
    return FaultSchedule(faults)


def encode_schedule(faults):
    """Return the compact JSON text of ``faults`` for an FMU's ``fault_schedule``."""
    return json.dumps([f.to_json() for f in faults], separators=(",", ":"))

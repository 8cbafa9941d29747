"""Free field and the room side by side: every fix-dependent claim judged in both.

The claims of the room's runs are built by the same table code as free field's (the same
margins, the same verdict rule of :mod:`orchestrator.reproduce.verdicts`); here they are
paired with their free-field twins by source, claim and condition. For every pair whose
verdict differs, the reason shown is measured, not supposed: the claim's effect in both
conditions and the localizer's fix errors in the cells it is about (RMS range and bearing
error, range bias, share of valid fixes; :func:`~orchestrator.reproduce.measures.fix_figures`).
"""

from dataclasses import dataclass, field

from orchestrator.files.json_policy import json_ready
from orchestrator.report.document import Code, Verdict

from .acoustics import CONDITION_LABELS, FREE_FIELD, ROOM
from .report import VERDICT_TONES as _TONES
from .statistics import CONFIDENCE

__all__ = ["ClaimPair", "SideBySide", "FIX_MEASURES", "side_by_side"]

# The localizer's figures shown beside the claims: key, header, format.
FIX_MEASURES = (("fix_range_rmse_m", "range RMSE [m]", ".3g"),
                ("fix_range_bias_m", "range bias [m]", ".3g"),
                ("fix_bearing_rmse_deg", "bearing RMSE [deg]", ".3g"),
                ("fix_valid_fraction", "valid fixes", ".3g"))


@dataclass
class ClaimPair:
    """One claim judged in free field and in the room (None where a condition lacks it)."""

    free_field: object
    room: object

    @property
    def key(self):
        claim = self.free_field or self.room
        return claim.source, claim.claim, claim.condition

    @property
    def differs(self):
        """True if both conditions judged the claim and gave different verdicts."""
        return (self.free_field is not None and self.room is not None
                and self.free_field.verdict != self.room.verdict)


def _effect(claim):
    if claim is None:
        return "-"
    return f"{claim.estimate.text('.4g')} {claim.unit}".strip() + f" ({claim.requirement()})"


def _verdict(claim):
    return "-" if claim is None else Verdict(claim.verdict, _TONES[claim.verdict])


def claim_cells(claim, cells):
    """The cells (names) a claim compares that ran in this study, for the fix errors."""
    return [c for c in claim.cells if c in cells]


def _pooled(analysis, cells, key):
    """Mean and interval of a figure over every run of the given cells."""
    from .statistics import mean_interval

    return mean_interval([v for cell in cells for v in analysis.values(cell, key)])


@dataclass
class SideBySide:
    """The claims of both conditions paired, the fix errors by cell, the room's geometry."""

    room: object
    pairs: list
    fix_rows: list
    clearance: dict
    reasons: dict = field(default_factory=dict)
    failed_runs: dict = field(default_factory=dict)

    def differing(self):
        """The pairs whose verdict differs between free field and room."""
        return [p for p in self.pairs if p.differs]

    def verdict_counts(self, condition):
        """How many claims got each verdict in one condition."""
        counts = {}
        for pair in self.pairs:
            claim = pair.free_field if condition == FREE_FIELD else pair.room
            if claim is not None:
                counts[claim.verdict] = counts.get(claim.verdict, 0) + 1
        return counts

    def headline(self):
        """The summary's line on the room."""
        differing = self.differing()
        counts = ", ".join(f"{n} {v}" for v, n in sorted(self.verdict_counts(ROOM).items()))
        return (f"In the room ({self.room.describe()}): {counts or 'no claims'}; "
                f"{len(differing)} of {len(self.pairs)} fix-dependent claims change verdict "
                "from free field (section 'Free field and room').")

    def add_to(self, document):
        """The section 'Free field and room': placement, the pairs, what differs and why."""
        level = int(round(100 * CONFIDENCE))
        section = document.section("Free field and room")
        section.paragraph([
            "The experiments whose results depend on the localizer's fixes (Tables 1-3, "
            "Sec. 6.2 with Figs. 7-8, 25 and 29) run in free field and in the room of ",
            Code(self.room.source), f": {self.room.describe()}. Each keeps the room's frame "
            "of that scenario: the robot starts at (0, 0) facing +y, 0.5 m from the wall "
            "behind it and centred across the room; Sec. 6.2's source stops 0.5 m short of "
            "the far wall in both conditions. Smallest clearance to a wall of the microphones "
            "at the start and the source's path: "
            + ", ".join(f"{name} {value:.3g} m" for name, value in sorted(self.clearance.items()))
            + ". Run i of a cell shares its draws in both conditions; a claim is judged in "
            f"each with the same rule and threshold rule ({level} % interval)."])
        if self.failed_runs:
            section.paragraph("Failed runs in the room (e.g. a body left it): " + ", ".join(
                f"{cell} {n}" for cell, n in sorted(self.failed_runs.items())) + ".")
        section.table(["source", "claim", "condition", "free field", "room",
                       "free-field effect (threshold)", "room effect (threshold)"],
                      [[*p.key[:2], p.key[2], _verdict(p.free_field), _verdict(p.room),
                        _effect(p.free_field), _effect(p.room)] for p in self.pairs],
                      caption=f"Every fix-dependent claim in both conditions ({len(self.pairs)})")
        differing = self.differing()
        section.paragraph(f"Claims whose verdict differs between free field and room "
                          f"({len(differing)}):")
        section.bullets([[f"{p.key[0]}: {p.key[1]} ({p.key[2]}): ", _verdict(p.free_field),
                          " -> ", _verdict(p.room), f". {self.reasons.get(p.key, '')}"]
                         for p in differing] or ["None: every verdict is the same in both."])
        section.table(["cell"] + [f"{header} {CONDITION_LABELS[c]}"
                                  for _, header, _ in FIX_MEASURES for c in (FREE_FIELD, ROOM)],
                      [[row["cell"]] + [row[key][c].text(fmt) if row[key][c].n else "-"
                                        for key, _, fmt in FIX_MEASURES
                                        for c in (FREE_FIELD, ROOM)]
                       for row in self.fix_rows],
                      caption=f"The localizer's fixes by cell, mean [{level} % interval] over "
                              "the runs")
        return section

    def to_dict(self):
        """JSON-able form."""
        return json_ready({
            "room": {"source": self.room.source, "parameters": self.room.parameters,
                     "description": self.room.describe()},
            "clearance_m": self.clearance,
            "failed_runs": self.failed_runs,
            "verdicts": {CONDITION_LABELS[c]: self.verdict_counts(c)
                         for c in (FREE_FIELD, ROOM)},
            "claims": [{"source": p.key[0], "claim": p.key[1], "condition": p.key[2],
                        "free_field": p.free_field.to_dict() if p.free_field else None,
                        "room": p.room.to_dict() if p.room else None,
                        "differs": p.differs, "why": self.reasons.get(p.key, "")}
                       for p in self.pairs],
            "fix_accuracy": [{"cell": row["cell"],
                              **{key: {CONDITION_LABELS[c]: row[key][c].to_dict()
                                       for c in (FREE_FIELD, ROOM)}
                                 for key, _, _ in FIX_MEASURES}} for row in self.fix_rows]})


def _reason(pair, analyses, cells):
    """What was measured for a differing pair: its effects and its cells' fix errors."""
    parts = [f"effect {_effect(pair.free_field)} in free field, {_effect(pair.room)} in the "
             "room"]
    chosen = claim_cells(pair.free_field, cells)
    for key, header, fmt in FIX_MEASURES[:3]:
        free, room = (_pooled(analyses[c], chosen, key) for c in (FREE_FIELD, ROOM))
        if free.n and room.n:
            parts.append(f"{header.split(' [')[0]} {free.mean:{fmt}} -> {room.mean:{fmt}}"
                         f" {header.split('[')[-1].rstrip(']')}")
    free, room = (_pooled(analyses[c], chosen, "fix_valid_fraction") for c in (FREE_FIELD, ROOM))
    if free.n and room.n:
        parts.append(f"valid fixes {100 * free.mean:.0f} -> {100 * room.mean:.0f} %")
    return "Measured: " + "; ".join(parts) + f" (cells {', '.join(chosen)})."


def side_by_side(free_claims, room_claims, analyses, room, clearance):
    """Pair the claims of both conditions and measure why differing verdicts differ.

    Parameters
    ----------
    free_claims, room_claims : list of Claim
        The fix-dependent claims judged on the free-field and on the room's runs.
    analyses : dict
        Condition -> :class:`~orchestrator.reproduce.analysis.Analysis` of its runs.
    room : Room
    clearance : dict
        Experiment -> smallest clearance to a wall [m]
        (:func:`~orchestrator.reproduce.acoustics.check_room_fits`).

    Returns
    -------
    SideBySide
    """
    in_room = {(c.source, c.claim, c.condition): c for c in room_claims}
    pairs = [ClaimPair(c, in_room.pop((c.source, c.claim, c.condition), None))
             for c in free_claims]
    pairs += [ClaimPair(None, c) for c in in_room.values()]
    cells = sorted(analyses[FREE_FIELD].cells)
    shown = [c for c in cells if c.startswith(("t13_", "sec62_"))
             and analyses[ROOM].has(c)]
    fix_rows = [{"cell": cell, **{key: {c: analyses[c].estimate(cell, key)
                                        for c in (FREE_FIELD, ROOM)}
                                  for key, _, _ in FIX_MEASURES}} for cell in shown]
    reasons = {p.key: _reason(p, analyses, cells) for p in pairs if p.differs}
    return SideBySide(room, pairs, fix_rows, clearance, reasons,
                      analyses[ROOM].failures())

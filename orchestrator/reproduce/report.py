"""The reproduction report: tables, claims, the paper-ratio table, figures; JSON, MD, HTML.

:meth:`Report.document` describes the report once (an
:class:`~orchestrator.report.document.Document`); :meth:`Report.write` renders it to
``reproduction.md`` and to ``reproduction.html`` (figures embedded) and writes
``reproduction.json`` under the JSON policy of :mod:`orchestrator.files.json_policy`
(a non-finite number is ``null``). Every path in the written files is relative to the
report's folder (figures as ``figures/fig07_....png``, runs as
``runs/<experiment>/runs/<hash>``), so the folder can be moved or published as it is.
"""

from dataclasses import dataclass, field
from pathlib import Path

from orchestrator.files.atomic import atomic_write_json
from orchestrator.files.json_policy import json_ready
from orchestrator.report.document import Code, Column, Document, Strong, Verdict
from orchestrator.report.html import write_html
from orchestrator.report.markdown import write_markdown

from .statistics import CONFIDENCE, INCONCLUSIVE, NOT_SUPPORTED, SUPPORTED, Estimate, judge

__all__ = ["Table", "Claim", "Comparison", "Figure", "Report", "VERDICT_TONES"]

# How each verdict is shown (the report's pass / fail / warn tones).
VERDICT_TONES = _TONES = {SUPPORTED: "pass", NOT_SUPPORTED: "fail", INCONCLUSIVE: "warn"}


def _estimate_text(estimate, fmt):
    """``mean [low, high]`` with the count of missing runs, or ``-`` without samples."""
    if estimate is None:
        return None
    return estimate.text(fmt) + (f" ({estimate.missing} missing)" if estimate.missing else "")


def _plain(value):
    """Inline content (a verdict, or a list of text and verdicts) as plain text."""
    if isinstance(value, Verdict):
        return value.text
    if isinstance(value, list) and any(isinstance(v, Verdict) for v in value):
        return "".join(_plain(v) for v in value)
    return value


def _cell(value, fmt):
    """A table cell: an :class:`Estimate` as its text, anything else as the value itself."""
    return _estimate_text(value, fmt) if isinstance(value, Estimate) else value


# Claims the summary names one by one, per verdict that is not "supported".
_HEADLINES_PER_VERDICT = 5


def _headlines(claims):
    """The summary's findings: the claims not supported, then the inconclusive ones, a few
    each, one line per claim, and how many more the claims tables hold."""
    lines = []
    for verdict in (NOT_SUPPORTED, INCONCLUSIVE):
        chosen = [c for c in claims if c.verdict == verdict]
        for claim in chosen[:_HEADLINES_PER_VERDICT]:
            lines.append([Verdict(verdict, _TONES[verdict]),
                          f": {claim.source}: {claim.claim} ({claim.condition}): "
                          f"{claim.estimate.text('.3g')} {claim.unit}, needs "
                          f"{claim.requirement()}"])
        if len(chosen) > _HEADLINES_PER_VERDICT:
            lines.append(f"... and {len(chosen) - _HEADLINES_PER_VERDICT} more {verdict} in "
                         "Claims and verdicts.")
    return lines or ["Every claim is supported."]


@dataclass
class Table:
    """One table: ``columns`` are ``(key, header, format)``; a cell is a label, a number, an
    :class:`Estimate` (mean [95 % interval]) or None."""

    name: str
    title: str
    columns: list
    rows: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def add_to(self, section):
        """Add the table (an :class:`Estimate` as ``mean [low, high]``) and its notes."""
        section.table([Column(header, format=fmt or "g") for _, header, fmt in self.columns],
                      [[_cell(row.get(key), fmt) for key, _, fmt in self.columns]
                       for row in self.rows])
        if self.notes:
            section.bullets(self.notes)
        return section

    def to_dict(self):
        """JSON-able form (a cell of inline content as its text)."""
        return {"title": self.title,
                "columns": [{"key": k, "header": h} for k, h, _ in self.columns],
                "rows": json_ready([{k: _plain(v) for k, v in row.items()}
                                    for row in self.rows]),
                "notes": list(self.notes)}


@dataclass
class Claim:
    """A claim of the paper judged on an interval against a stated threshold.

    ``estimate`` is the interval of what the claim is about (a mean paired difference, a
    mean slope, a mean figure); the claim holds if its true value lies ``claimed``
    ("above" / "below") ``threshold``. The verdict is computed, never set by hand.
    """

    source: str
    claim: str
    condition: str
    measure: str
    estimate: Estimate
    threshold: float
    claimed: str
    unit: str = ""
    paper: str = ""
    reason: str = ""

    @property
    def verdict(self):
        """supported / not supported / inconclusive (:func:`statistics.judge`)."""
        return judge(self.estimate, self.threshold, self.claimed)

    def likely_reason(self):
        """Why the simulation may differ from the paper, when the claim is not supported."""
        return "" if self.verdict == "supported" else self.reason

    def requirement(self):
        """The threshold as text, e.g. ``"< -0.0120 m"``."""
        sign = ">" if self.claimed == "above" else "<"
        return f"{sign} {self.threshold:.4g} {self.unit}".strip()

    def to_dict(self):
        """JSON-able form."""
        return {"source": self.source, "claim": self.claim, "condition": self.condition,
                "measure": self.measure, "estimate": self.estimate.to_dict(),
                "threshold": json_ready(self.threshold), "claimed": self.claimed,
                "unit": self.unit, "requirement": self.requirement(), "paper": self.paper,
                "verdict": self.verdict, "likely_reason": self.likely_reason()}


@dataclass
class Comparison:
    """One printed number of the paper beside the simulated mean and interval."""

    table: str
    row: str
    quantity: str
    paper: float
    estimate: Estimate
    note: str = ""

    @property
    def ratio(self):
        """Simulated mean / paper value (None if either is missing or the paper's is 0)."""
        if self.paper in (None, 0) or self.estimate is None or self.estimate.n == 0:
            return None
        return self.estimate.mean / self.paper

    def to_dict(self):
        """JSON-able form."""
        return {"table": self.table, "row": self.row, "quantity": self.quantity,
                "paper": self.paper, "simulated": json_ready(self.estimate),
                "ratio": json_ready(self.ratio), "note": self.note}


@dataclass
class Figure:
    """A written PNG: its name after the paper's figure, a caption, the path (relative)."""

    name: str
    caption: str
    path: str
    series: list = field(default_factory=list)

    def to_dict(self):
        """JSON-able form."""
        return {"name": self.name, "caption": self.caption, "path": self.path,
                "series": list(self.series)}


@dataclass
class Report:
    """Everything the study found, and the files it wrote."""

    configuration: dict
    tolerances: list
    definitions: dict
    tables: dict
    claims: list
    comparisons: list
    figures: list = field(default_factory=list)
    settings: dict = field(default_factory=dict)
    side_by_side: object = None     # SideBySide: the fix-dependent claims in free field and room
    out_dir: Path = None
    markdown_path: Path = None
    json_path: Path = None
    html_path: Path = None

    def verdict_counts(self):
        """How many claims got each verdict."""
        counts = {}
        for claim in self.claims:
            counts[claim.verdict] = counts.get(claim.verdict, 0) + 1
        return counts

    def to_dict(self):
        """JSON-able form (no absolute paths)."""
        return {"configuration": self.configuration,
                "tolerances": [{"parameter": t.parameter, "band": t.band(),
                                "justification": t.justification} for t in self.tolerances],
                "settings": json_ready(self.settings), "definitions": self.definitions,
                "tables": {name: t.to_dict() for name, t in self.tables.items()},
                "claims": [c.to_dict() for c in self.claims],
                "verdicts": self.verdict_counts(),
                "paper_ratios": [c.to_dict() for c in self.comparisons],
                "figures": [f.to_dict() for f in self.figures],
                "free_field_and_room": (self.side_by_side.to_dict()
                                        if self.side_by_side is not None else None)}

    def document(self):
        """The report as one document, rendered to both Markdown and HTML."""
        level = int(round(100 * CONFIDENCE))
        s = self.settings
        # the stated assumptions come first (docs/reproduction.md): no lead paragraph
        document = Document(
            "Paper reproduction: Monte Carlo study beside the paper's printed figures")
        section = document.section("Configuration and assumptions")
        section.table(["assumption", "value"], [[k, v] for k, v in self.configuration.items()])
        section.paragraph(
            f"Monte Carlo: {s.get('runs_per_cell')} runs per cell, {s.get('runs_total')} runs "
            f"in all ({s.get('runs_computed')} computed, {s.get('runs_reused')} reused from "
            f"disk), study seed {s.get('study_seed')}; every figure is the mean over a cell's "
            f"runs with its {level} % Student-t interval 'mean [low, high]'. Stop times x"
            f"{s.get('stop_time_scale')}. Wall time {s.get('wall_time_s', 0):.0f} s on "
            f"{s.get('workers')} worker(s).")
        section.paragraph(["Varied in every run (uniform in the band around the cell's "
                           "nominal; ", Code("orchestrator/data/tolerances.toml"),
                           "), plus the localizer's noise seed:"])
        section.table(["parameter", "band", "justification"],
                      [[Code(t.parameter), t.band(), t.justification] for t in self.tolerances])
        counts = self.verdict_counts()
        room = [self.side_by_side.headline()] if self.side_by_side is not None else []
        document.summarize([(verdict, counts.get(verdict, 0), _TONES[verdict])
                            for verdict in (SUPPORTED, NOT_SUPPORTED, INCONCLUSIVE)],
                           room + _headlines(self.claims))
        section = document.section("Claims and verdicts")
        section.paragraph([
            f"Each claim is judged on the {level} % interval of the quantity in 'measure' (a "
            "mean paired difference between cells whose run i shares its draws, a mean per-run "
            "slope over all speeds, or a mean figure): ", Strong(SUPPORTED), " if the whole "
            "interval lies beyond the threshold on the claimed side, ", Strong(NOT_SUPPORTED),
            " if it lies wholly on the other side, ", Strong(INCONCLUSIVE), " if it straddles "
            "the threshold. An interval followed by '(N missing)' leaves out N runs of the cell "
            "that gave no value (e.g. the robot never arrived). One table per verdict:"])
        for verdict in (NOT_SUPPORTED, INCONCLUSIVE, SUPPORTED):
            claims = [c for c in self.claims if c.verdict == verdict]
            if claims:
                section.table(["source", "claim", "condition", "measure",
                               f"{level} % interval", "threshold", "paper", "verdict",
                               "likely reason (where not supported)"],
                              [[c.source, c.claim, c.condition, c.measure,
                                f"{c.estimate.text('.4g')} {c.unit}".strip(), c.requirement(),
                                c.paper, Verdict(c.verdict, _TONES[c.verdict]),
                                c.likely_reason()] for c in claims],
                              caption=f"Claims {verdict} ({len(claims)})")
        if self.side_by_side is not None:
            self.side_by_side.add_to(document)
        section = document.section("Figures")
        for figure in self.figures:
            section.figure(figure.path, f"{figure.name}: {figure.caption}", alt=figure.name)
        if not self.figures:
            section.paragraph("No figures.")
        for table in self.tables.values():
            table.add_to(document.section(table.title))
        document.section("Every number of the paper beside the simulation").table(
            ["table", "row", "quantity", Column("paper", format="g"),
             f"simulated mean [{level} % interval]", Column("sim / paper", format=".4g")],
            [[c.table, c.row, c.quantity, c.paper, _estimate_text(c.estimate, ".4g"), c.ratio]
             for c in self.comparisons])
        document.section("Definitions").bullets([[Code(k), f": {v}"]
                                                 for k, v in self.definitions.items()])
        return document

    def write(self, out_dir):
        """Write ``reproduction.json``, ``reproduction.md`` and ``reproduction.html``."""
        out_dir = Path(out_dir)
        self.json_path = out_dir / "reproduction.json"
        atomic_write_json(self.json_path, self.to_dict(), fsync=False)
        document = self.document()
        self.markdown_path = write_markdown(document, out_dir / "reproduction.md",
                                            html_companion="reproduction.html")
        self.html_path = write_html(document, out_dir / "reproduction.html")
        return self

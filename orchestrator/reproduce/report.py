"""The reproduction report: tables, claims, the paper-ratio table, figures; JSON, MD, HTML.

:meth:`Report.document` describes the report once (an
:class:`~orchestrator.report.document.Document`); :meth:`Report.write` renders it to
``reproduction.md`` and to ``reproduction.html`` (figures embedded) and writes
``reproduction.json`` under the JSON policy of :mod:`orchestrator.files.json_policy`
(a non-finite number is ``null``). Every path in the written files is relative to the
report's folder (figures as ``figures/fig07_....png``, runs as
``runs/<experiment>/runs/<hash>``), so the folder can be moved or published as it is.
"""

import math
from dataclasses import dataclass, field
from pathlib import Path

from orchestrator.files.atomic import atomic_write_json
from orchestrator.files.json_policy import json_ready
from orchestrator.report.document import Code, Column, Document, Strong, Verdict
from orchestrator.report.html import write_html
from orchestrator.report.markdown import write_markdown

from .verdicts import CONTRADICTED, INCONCLUSIVE, NO_EFFECT, SUPPORTED, WEAKER
from .statistics import CONFIDENCE, Estimate

__all__ = ["Table", "Comparison", "Figure", "Report", "VERDICTS", "VERDICT_TONES"]

# The verdicts, worst first as the summary lists them, and how each is shown (the report's
# pass / fail / warn tones).
VERDICTS = (CONTRADICTED, NO_EFFECT, WEAKER, INCONCLUSIVE, SUPPORTED)
VERDICT_TONES = _TONES = {SUPPORTED: "pass", WEAKER: "warn", NO_EFFECT: "fail",
                          CONTRADICTED: "fail", INCONCLUSIVE: "warn"}


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
    """The summary's findings: the paper's claims not supported, worst verdict first, a few
    each, one line per claim, and how many more the claims tables hold."""
    lines = []
    for verdict in VERDICTS[:-1]:
        chosen = [c for c in claims if c.verdict == verdict and c.tally]
        for claim in chosen[:_HEADLINES_PER_VERDICT]:
            lines.append([Verdict(verdict, _TONES[verdict]),
                          f": {claim.source}: {claim.claim} ({claim.condition}, against "
                          f"{claim.comparator}): {_effect(claim)}. Decided: "
                          f"{claim.judged.verdict.rule}"])
        if len(chosen) > _HEADLINES_PER_VERDICT:
            lines.append(f"... and {len(chosen) - _HEADLINES_PER_VERDICT} more {verdict} in "
                         "Claims and verdicts.")
    return lines or ["Every claim of the paper is supported."]


def _effect(claim):
    """Ours, the paper's and their ratio, as text."""
    judged = claim.judged
    text = f"ours {claim.estimate.text('.3g')} {claim.unit}".rstrip()
    if claim.paper is not None:
        text += f", paper {claim.paper:.3g}"
        if judged.ratio is not None and math.isfinite(judged.ratio):
            text += f" (ratio {judged.ratio:.2f})"
    return text


def _statistics(claim):
    """The sign test, failed and lost runs and the interval's rule, as text."""
    found = claim.judged.evidence
    return found.text() + (f" ({found.rule})" if found.method == "median" else "")


_CLAIM_COLUMNS = ["source", "claim", "condition", "against", "measure", "ours, paper (ratio)",
                  "threshold and margin", "statistics", "verdict", "reason (measured)"]


def _claim_row(claim):
    return [claim.source, claim.claim, claim.condition, claim.comparator, claim.measure,
            _effect(claim), claim.requirement(), _statistics(claim),
            Verdict(claim.verdict, _TONES[claim.verdict]), claim.reason]


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
        """How many of the paper's claims (once per condition) got each verdict."""
        counts = {}
        for claim in self.claims:
            if claim.tally:
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
            f"disk), study seed {s.get('study_seed')}; every figure is an estimate over a cell's "
            f"runs with its {level} % interval 'estimate [low, high]': the mean and its "
            "Student-t interval, or, marked '(median)', the median and its rank-based interval "
            "where runs gave no value or the values separate (Claims and verdicts). Stop times x"
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
                            for verdict in VERDICTS],
                           room + _headlines(self.claims))
        section = document.section("Claims and verdicts")
        section.paragraph([
            "Each claim is judged on one value per run of what it is about (a paired "
            "difference between cells whose run i shares its draws, a per-run slope over the "
            "speeds, or a figure against a bound), in the direction the paper claims, beside "
            "the paper's own magnitude where it prints one: ", Strong(SUPPORTED),
            " (the claimed direction, at least half the paper's magnitude), ", Strong(WEAKER),
            " (the claimed direction, smaller), ", Strong(NO_EFFECT), " (the whole interval "
            "inside the stated equivalence margin), ", Strong(CONTRADICTED), " (the opposite "
            "direction beyond the margin), ", Strong(INCONCLUSIVE), " (none of these). "
            f"The interval is the {level} % Student-t interval of the mean, or, where a cell "
            "has lost runs or a bimodal sample, the rank-based interval of the median (its "
            "rule is named in each row); a paired sign test and the count of lost runs (never "
            "arrived, or failed) stand beside it. A lost run counts as the worst outcome on "
            "its side. The tally counts the paper's claims, once per condition; design "
            "comparisons of ours are listed apart. The reason is measured in the compared "
            "cells (medians), not supposed."])
        paper_claims = [c for c in self.claims if c.tally]
        for verdict in VERDICTS:
            claims = [c for c in paper_claims if c.verdict == verdict]
            if claims:
                section.table(_CLAIM_COLUMNS, [_claim_row(c) for c in claims],
                              caption=f"Claims {verdict} ({len(claims)})")
        design = [c for c in self.claims if not c.tally]
        if design:
            section.table(_CLAIM_COLUMNS, [_claim_row(c) for c in design],
                          caption=f"Design comparisons, not claims of the paper ({len(design)})")
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

"""The reproduction report: tables, claims, the paper-ratio table, figures; JSON, MD, HTML.

Every path in the written files is relative to the report's folder (figures as
``figures/fig07_....png``, runs as ``runs/<experiment>/runs/<hash>``), so the folder can be
moved or published as it is. The HTML is written by the shared
:mod:`orchestrator.report.html` module with the figures embedded.
"""

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .statistics import CONFIDENCE, Estimate, judge

__all__ = ["Table", "Claim", "Comparison", "Figure", "Report"]


def _cell_text(value, fmt):
    if value is None:
        return "-"
    if isinstance(value, Estimate):
        text = value.text(fmt)
        return text + (f" ({value.missing} missing)" if value.missing else "")
    if isinstance(value, float):
        if not math.isfinite(value):
            return "inf" if value > 0 else "nan"
        return format(value, fmt) if fmt else f"{value:g}"
    return str(value)


def jsonable(value):
    """Plain JSON types: Estimates as dicts, numpy numbers as floats, non-finite as None."""
    if isinstance(value, Estimate):
        return value.to_dict()
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, Path):
        return value.as_posix()
    return value


@dataclass
class Table:
    """One table: ``columns`` are ``(key, header, format)``; a cell is a label, a number, an
    :class:`Estimate` (mean [95 % interval]) or None."""

    name: str
    title: str
    columns: list
    rows: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def to_markdown(self):
        """GitHub Markdown with the notes below."""
        lines = [f"### {self.title}", "",
                 "| " + " | ".join(header for _, header, _ in self.columns) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        for row in self.rows:
            lines.append("| " + " | ".join(_cell_text(row.get(key), fmt)
                                           for key, _, fmt in self.columns) + " |")
        if self.notes:
            lines.append("")
            lines += [f"- {note}" for note in self.notes]
        return "\n".join(lines) + "\n"

    def to_dict(self):
        """JSON-able form."""
        return {"title": self.title,
                "columns": [{"key": k, "header": h} for k, h, _ in self.columns],
                "rows": jsonable(self.rows), "notes": list(self.notes)}


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
                "threshold": jsonable(self.threshold), "claimed": self.claimed,
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
                "paper": self.paper, "simulated": jsonable(self.estimate),
                "ratio": jsonable(self.ratio), "note": self.note}


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
                "settings": jsonable(self.settings), "definitions": self.definitions,
                "tables": {name: t.to_dict() for name, t in self.tables.items()},
                "claims": [c.to_dict() for c in self.claims],
                "verdicts": self.verdict_counts(),
                "paper_ratios": [c.to_dict() for c in self.comparisons],
                "figures": [f.to_dict() for f in self.figures]}

    def sections(self):
        """The report as ``(heading, markdown)`` sections, shared by the MD and the HTML."""
        level = int(round(100 * CONFIDENCE))
        s = self.settings
        config = ["| assumption | value |", "|---|---|"]
        config += [f"| {k} | {v} |" for k, v in self.configuration.items()]
        config += ["", f"Monte Carlo: {s.get('runs_per_cell')} runs per cell, "
                   f"{s.get('runs_total')} runs in all ({s.get('runs_computed')} computed, "
                   f"{s.get('runs_reused')} reused from disk), study seed "
                   f"{s.get('study_seed')}; every figure is the mean over a cell's runs with "
                   f"its {level} % Student-t interval `mean [low, high]`. Stop times x"
                   f"{s.get('stop_time_scale')}. Wall time {s.get('wall_time_s', 0):.0f} s "
                   f"on {s.get('workers')} worker(s).", "",
                   "Varied in every run (uniform in the band around the cell's nominal; "
                   "`orchestrator/data/tolerances.toml`), plus the localizer's noise seed:", "",
                   "| parameter | band | justification |", "|---|---|---|"]
        config += [f"| `{t.parameter}` | {t.band()} | {t.justification} |"
                   for t in self.tolerances]
        counts = self.verdict_counts()
        verdicts = [
            f"Each claim is judged on the {level} % interval of the quantity in 'measure' "
            "(a mean paired difference between cells whose run i shares its draws, a mean "
            "per-run slope over all speeds, or a mean figure): **supported** if the whole "
            "interval lies beyond the threshold on the claimed side, **not supported** if it "
            "lies wholly on the other side, **inconclusive** if it straddles the threshold. "
            "Totals: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".", "",
            "| source | claim | condition | measure | interval | threshold | paper | verdict "
            "| likely reason (where not supported) |",
            "|---|---|---|---|---|---|---|---|---|"]
        for c in self.claims:
            verdicts.append(f"| {c.source} | {c.claim} | {c.condition} | {c.measure} | "
                            f"{c.estimate.text('.4g')} {c.unit} | {c.requirement()} | "
                            f"{c.paper} | **{c.verdict}** | {c.likely_reason()} |")
        ratios = ["| table | row | quantity | paper | simulated mean [95 % interval] | "
                  "sim / paper |", "|---|---|---|---|---|---|"]
        for c in self.comparisons:
            ratio = "-" if c.ratio is None else f"{c.ratio:.2f}"
            ratios.append(f"| {c.table} | {c.row} | {c.quantity} | {c.paper:g} | "
                          f"{_cell_text(c.estimate, '.4g')} | {ratio} |")
        sections = [("Configuration and assumptions", "\n".join(config)),
                    ("Claims and verdicts", "\n".join(verdicts))]
        for table in self.tables.values():
            body = table.to_markdown().split("\n", 2)[2]
            sections.append((table.title, body))
        sections.append(("Every number of the paper beside the simulation", "\n".join(ratios)))
        figures = [f"**{f.name}**: {f.caption}\n\n![{f.name}]({f.path})\n"
                   for f in self.figures]
        sections.append(("Figures", "\n".join(figures) or "No figures."))
        definitions = [f"- `{k}`: {v}" for k, v in self.definitions.items()]
        sections.append(("Definitions", "\n".join(definitions)))
        return sections

    def to_markdown(self):
        """The whole report as Markdown (figures linked relatively)."""
        lines = ["# Paper reproduction: Monte Carlo study beside the paper's printed figures",
                 ""]
        for heading, body in self.sections():
            lines += [f"## {heading}", "", body.rstrip(), ""]
        return "\n".join(lines)

    def write(self, out_dir):
        """Write ``reproduction.json``, ``reproduction.md`` and ``reproduction.html``."""
        out_dir = Path(out_dir)
        self.json_path = out_dir / "reproduction.json"
        self.json_path.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        self.markdown_path = out_dir / "reproduction.md"
        self.markdown_path.write_text(self.to_markdown())
        self.html_path = _write_html(self, out_dir)
        return self


def _write_html(report, out_dir):
    """The same content as the Markdown, through the shared self-contained HTML writer."""
    from orchestrator.report.html import Column, HtmlReport

    level = int(round(100 * CONFIDENCE))
    st = report.settings
    page = HtmlReport(
        "Paper reproduction: Monte Carlo study beside the paper's printed figures",
        intro=f"{st.get('runs_per_cell')} runs per cell, {st.get('runs_total')} runs; every "
              f"figure is the mean over a cell's runs with its {level} % Student-t interval "
              "'mean [low, high]'. Claims are judged on intervals against the stated "
              "thresholds.")
    section = page.section("Configuration and assumptions")
    section.table([Column("assumption"), Column("value")],
                  [[k, v] for k, v in report.configuration.items()])
    section.paragraph("Varied in every run (uniform in the band around the cell's nominal; "
                      "orchestrator/data/tolerances.toml), plus the localizer's noise seed.")
    section.table([Column("parameter"), Column("band"), Column("justification")],
                  [[t.parameter, t.band(), t.justification] for t in report.tolerances])
    section.paragraph(f"Wall time {st.get('wall_time_s', 0):.0f} s on {st.get('workers')} "
                      f"worker(s); {st.get('runs_computed')} runs computed, "
                      f"{st.get('runs_reused')} reused; stop times x"
                      f"{st.get('stop_time_scale')}.")
    section = page.section("Claims and verdicts")
    counts = report.verdict_counts()
    section.paragraph("Supported: the whole interval lies beyond the threshold on the claimed "
                      "side; not supported: wholly on the other side; inconclusive: it "
                      "straddles the threshold. Totals: "
                      + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".")
    section.table([Column(h) for h in ("source", "claim", "condition", "measure",
                                       f"{level} % interval", "threshold", "paper",
                                       "verdict", "likely reason (where not supported)")],
                  [[c.source, c.claim, c.condition, c.measure,
                    f"{c.estimate.text('.4g')} {c.unit}".strip(), c.requirement(), c.paper,
                    c.verdict, c.likely_reason()] for c in report.claims])
    for table in report.tables.values():
        section = page.section(table.title)
        section.table([Column(header) for _, header, _ in table.columns],
                      [[_cell_text(row.get(key), fmt) for key, _, fmt in table.columns]
                       for row in table.rows])
        if table.notes:
            section.bullets(table.notes)
    section = page.section("Every number of the paper beside the simulation")
    section.table([Column(h) for h in ("table", "row", "quantity", "paper",
                                       f"simulated mean [{level} % interval]",
                                       "sim / paper")],
                  [[c.table, c.row, c.quantity, c.paper, _cell_text(c.estimate, ".4g"),
                    c.ratio] for c in report.comparisons])
    section = page.section("Figures")
    for figure in report.figures:
        section.figure(out_dir / figure.path, f"{figure.name}: {figure.caption}")
    page.section("Definitions").bullets([f"{k}: {v}" for k, v in report.definitions.items()])
    return page.write(out_dir / "reproduction.html")

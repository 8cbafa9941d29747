"""The report document model: one document, two renderings with the same cells and verdicts."""

import html
import math
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from components.common.errors import ConfigError
from orchestrator.report.document import (
    EMPTY_CELL, Code, Column, Document, Link, Paragraph, Table, Verdict, cell,
)
from orchestrator.report.html import render_html
from orchestrator.report.markdown import render_markdown


class _Tables(HTMLParser):
    """Every table of a page as rows of cell texts (headers included), and each cell's class."""

    def __init__(self):
        super().__init__()
        self.tables, self.classes, self._cell = [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
            self.classes.append(dict(attrs).get("class"))

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append("".join(self._cell))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def html_tables(page):
    parser = _Tables()
    parser.feed(page)
    return parser.tables, parser.classes


def markdown_tables(text):
    """Every pipe table as rows of cell texts, as a Markdown reader shows them."""
    tables, current = [], None
    for line in text.splitlines():
        if not line.startswith("|"):
            current = None
            continue
        if re.fullmatch(r"\|(---\|)+", line):
            continue
        if current is None:
            current = []
            tables.append(current)
        cells = re.split(r"(?<!\\)\|", line)[1:-1]
        current.append([html.unescape(re.sub(r"\*\*(.*?)\*\*|`(.*?)`", r"\1\2",
                                             c.strip().replace("\\|", "|"))) for c in cells])
    return tables


def _checks_document():
    document = Document("Checks <b>report</b>")
    document.section("Checks").table(
        ["check", Column("margin", "dB", ".2f"), Column("count", None, "d"), "ok", "verdict"],
        [["gain_margin", 12.3456, 4, True, Verdict("pass", "pass")],
         ["phase | margin", float("nan"), 5, False, Verdict("FAIL", "fail")],
         ["<script>alert(1)</script>", None, np.int64(7), np.float64(math.inf),
          Verdict("warning", "warn")],
         [Code("step_response"), np.float32(0.5), -1, "a & b", "plain"]],
        caption="The verdicts")
    return document


def test_markdown_and_html_show_the_same_cells_and_verdicts():
    document = _checks_document()
    html_page = render_html(document)
    (from_html,), classes = html_tables(html_page)
    (from_markdown,) = markdown_tables(render_markdown(document))
    assert from_markdown == from_html
    assert from_html == [
        ["check", "margin [dB]", "count", "ok", "verdict"],
        ["gain_margin", "12.35", "4", "yes", "pass"],
        ["phase | margin", EMPTY_CELL, "5", "no", "FAIL"],
        ["<script>alert(1)</script>", EMPTY_CELL, "7", "inf", "warning"],
        ["step_response", "0.50", "-1", "a & b", "plain"]]
    # numbers right-aligned, each verdict in its tone
    assert classes[5:10] == [None, "num", "num", None, "pass"]
    assert [c for c in classes if c in ("pass", "fail", "warn")] == ["pass", "fail", "warn"]


def test_every_block_appears_in_both_renderings_in_the_same_order():
    document = Document("Report", intro=["Read ", Code("docs/x.md"), "."], contents=False)
    section = document.section("First")
    section.paragraph("alpha paragraph", tone="warn").bullets(["beta item", ["gamma ", Code("c")]])
    section.preformatted("delta pre")
    document.section("Second", level=3).table(["epsilon"], [["zeta"]], caption="eta caption")
    document.section("Third").figure("figures/f.png", "theta caption")
    markdown = render_markdown(document)
    words = ["docs/x.md", "First", "alpha", "beta", "gamma", "delta", "Second", "eta caption",
             "epsilon", "zeta", "Third", "theta"]
    assert [markdown.index(w) for w in words] == sorted(markdown.index(w) for w in words)
    assert "### Second" in markdown and "```\ndelta pre\n```" in markdown
    assert "![theta caption](figures/f.png)" in markdown
    with pytest.raises(ConfigError, match="f.png"):      # the HTML embeds it: the file must exist
        render_html(document)
    del document.sections[-1]
    page = render_html(document)
    assert [page.index(w) for w in words[:-2]] == sorted(page.index(w) for w in words[:-2])
    assert '<p class="warn">alpha paragraph</p>' in page


@pytest.mark.parametrize("value, column, expected", [
    (None, Column("x"), (EMPTY_CELL, True)),
    (float("nan"), Column("x", format=".2f"), (EMPTY_CELL, True)),
    (np.float32("nan"), Column("x"), (EMPTY_CELL, True)),
    (1.23456, Column("x"), ("1.235", True)),
    (1.23456, Column("x", format=".1f"), ("1.2", True)),
    (-math.inf, Column("x"), ("-inf", True)),
    (True, Column("x"), ("yes", False)),
    (np.bool_(False), Column("x"), ("no", False)),
    (3, Column("x", format=".2f"), ("3.00", True)),
    (3, Column("x"), ("3", True)),
    (np.int64(7), Column("x", format="03d"), ("007", True)),
    ("3", Column("x", format=".2f"), ("3", False)),
], ids=["none", "nan", "numpy-nan", "default-format", "column-format", "inf", "bool",
        "numpy-bool", "int-formatted", "int", "numpy-int", "text"])
def test_cells_read_the_same_everywhere(value, column, expected):
    assert cell(value, column) == expected


def test_bad_tables_links_and_text_are_refused_with_their_names():
    with pytest.raises(ConfigError, match=r"'margins': row 1 has 1 cells for 2 columns"):
        Table(["a", "b"], [[1, 2], [3]], caption="margins")
    with pytest.raises(ConfigError, match="relative path"):
        Link("x", "/etc/passwd")
    with pytest.raises(ConfigError, match="tone = 'green', valid: pass, fail, warn"):
        Verdict("ok", "green")
    with pytest.raises(ConfigError, match="not text"):
        Paragraph(["fine", 3.0])
    with pytest.raises(ConfigError, match="level = 1"):
        Document("t").section("s", level=1)

"""The Markdown rendering: text never becomes markup, figures are linked inside the folder."""

import pytest

from components.common.errors import ConfigError
from orchestrator.report.document import Code, Document, Link, Verdict
from orchestrator.report.markdown import render_markdown, write_markdown


def test_text_cannot_open_tags_entities_or_table_cells():
    document = Document("A <b>title</b>")
    section = document.section("Cells & <i>x</i>")
    section.paragraph(["a < b, x &lt; y, ", Code("a`b"), " ", Verdict("FAIL", "fail")])
    section.table(["a|b", "c"], [["1 | 2", "<script>alert(1)</script>"],
                                 ["two\nlines", Code("x|y")]])
    text = render_markdown(document)
    assert text.startswith("# A &lt;b>title&lt;/b>\n")
    assert "## Cells & &lt;i>x&lt;/i>" in text
    # a lone '<' stays readable; one that would open a tag or an entity does not
    assert "a < b, x &amp;lt; y, ``a`b`` **FAIL**" in text
    assert "| a\\|b | c |" in text
    assert "| 1 \\| 2 | &lt;script>alert(1)&lt;/script> |" in text
    assert "| two lines | `x\\|y` |" in text
    assert "<script>" not in text and "<b>" not in text


def test_figures_and_links_stay_inside_the_folder():
    document = Document("r")
    section = document.section("s").bullets([Link("data", "sub/data.json")])
    section.figure("figures/fig 1.png", "Fig. 1: paths", alt="Fig. 1")
    text = render_markdown(document, html_companion="r.html")
    assert "[r.html](r.html)" in text.split("## s")[0]
    assert "- [data](sub/data.json)" in text
    assert "![Fig. 1](figures/fig%201.png)\n\n*Figure 1. Fig. 1: paths*" in text
    for source in ("/tmp/fig.png", "../fig.png", b"\x89PNG\r\n\x1a\n"):
        bad = Document("r")
        bad.section("s").figure(source, "a figure")
        with pytest.raises(ConfigError, match="'a figure'"):
            render_markdown(bad)


def test_write_markdown_replaces_the_file_whole(tmp_path):
    path = tmp_path / "out" / "report.md"
    document = Document("Gain \u00b5")
    assert write_markdown(document, path) == path
    assert path.read_text(encoding="utf-8") == "# Gain \u00b5\n"
    assert [p.name for p in path.parent.iterdir()] == ["report.md"]


def test_the_markdown_answers_first_and_its_contents_link_to_github_anchors():
    from orchestrator.report.document import LONG_TABLE_ROWS, Verdict

    document = Document("Study")
    document.summarize([("supported", 2, "pass"), ("not supported", 1, "fail")],
                       ["claim `x` is **not** supported"])
    document.section("Claims: 95 % interval").table(
        ["claim", "verdict"], [[f"c{i}", Verdict("supported", "pass")]
                               for i in range(LONG_TABLE_ROWS + 1)], caption="All claims")
    document.section("Figures")
    document.section("Figures")          # a repeated heading gets GitHub's -1
    text = render_markdown(document)
    assert text.index("## Summary") < text.index("## Contents") < text.index("## Claims")
    assert "**2 supported** \u00b7 **1 not supported**" in text
    assert "- claim `x` is **not** supported" in text
    # GitHub's anchors: lower case, punctuation dropped, spaces as hyphens; repeats numbered
    assert "- [Claims: 95 % interval](#claims-95--interval)" in text
    assert "- [Figures](#figures)\n- [Figures](#figures-1)" in text
    assert "<details><summary>All claims (21 rows; click to open)</summary>\n\n| claim |" in text

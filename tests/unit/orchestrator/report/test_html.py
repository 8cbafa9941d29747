"""The shared HTML report writer: escaping, tables with units, embedded figures, a real browser."""

import base64
import html
import os
import re
import struct
import zlib

import pytest

from components.common.errors import ConfigError
from orchestrator.report.document import Code, Document, Link, Strong, Verdict
from orchestrator.report.html import (
    Column, HtmlReport, embedded_image_sources, link, png_data_uri, write_html,
)
from tests.support.html_render import ChromiumUnavailable, chromium_path, render_image_count


def _png(width, height):
    """A valid RGB PNG written by hand (independent of matplotlib)."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + b"\xff\x00\x00" * width for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def _report(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    png_file = tmp_path / "red.png"
    png_file.write_bytes(_png(7, 5))
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    report = HtmlReport("Report <&> test", intro="a < b & c")
    section = report.section("Figures & tables")
    section.figure(png_file, "from a file")
    section.figure(fig, "from matplotlib")
    section.figure(_png(3, 3), "from bytes")
    section.table([Column("kp"), Column("margin", "dB", ".2f"), "ok", Column("n", None, "d")],
                  [[3.0, 12.3456, True, 4], [float("nan"), None, False, 5]],
                  caption="margins")
    section.bullets(["<script>alert(1)</script>", link("data", "sub/figures.json")])
    plt.close(fig)
    return report


def test_text_is_escaped_and_tables_show_units_and_formats(tmp_path):
    page = _report(tmp_path).render()
    assert "<title>Report &lt;&amp;&gt; test</title>" in page
    assert "a &lt; b &amp; c" in page
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "<th>margin [dB]</th>" in page and "<th>kp</th>" in page
    assert '<td class="num">12.35</td>' in page and "<td>yes</td>" in page
    assert "<td>no</td>" in page and '<td class="num">4</td>' in page
    assert page.count('<td class="num">\u2014</td>') == 2
    assert '<a href="sub/figures.json">data</a>' in page


def test_every_figure_is_embedded_png_and_nothing_points_outside(tmp_path):
    page = _report(tmp_path).render()
    sources = embedded_image_sources(page)
    assert len(sources) == 3
    for source in sources:
        assert source.startswith("data:image/png;base64,")
        assert base64.b64decode(source.split(",", 1)[1]).startswith(b"\x89PNG\r\n\x1a\n")
    # The bytes round-trip exactly.
    assert base64.b64decode(sources[2].split(",", 1)[1]) == _png(3, 3)
    assert not re.search(r"(?:src|href)=\"(?:https?:|//|/|file:)", page)
    assert str(tmp_path) not in page


@pytest.mark.parametrize("target", ["/etc/passwd", "../up.json", "https://example.org/x",
                                    "file:///tmp/x"], ids=["absolute", "parent", "url", "file"])
def test_links_outside_the_folder_are_refused(target):
    with pytest.raises(ConfigError, match="relative path"):
        link("x", target)


def test_bad_figures_and_rows_are_refused(tmp_path):
    (tmp_path / "fake.png").write_text("not a png")
    with pytest.raises(ConfigError, match="not a PNG"):
        png_data_uri(tmp_path / "fake.png")
    with pytest.raises(ConfigError, match="file not found"):
        png_data_uri(tmp_path / "missing.png")
    with pytest.raises(ConfigError, match="row 0 has 1 cells for 2 columns"):
        HtmlReport("t").section("s").table(["a", "b"], [[1]])


def test_write_is_atomic_and_utf8(tmp_path):
    path = HtmlReport("Gain \u00b5 report").write(tmp_path / "out" / "r.html")
    assert path.read_text(encoding="utf-8").count("Gain \u00b5 report") == 2
    assert [p.name for p in path.parent.iterdir()] == ["r.html"]
    mask = os.umask(0)
    os.umask(mask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask  # not mkstemp's 0600


def _broken_page(tmp_path):
    """A page whose second image is PNG-headed garbage: a browser cannot decode it."""
    report = HtmlReport("broken")
    report.section("s").figure(_png(4, 4), "good").figure(
        b"\x89PNG\r\n\x1a\n" + b"\x00" * 40, "truncated")
    return report.write(tmp_path / "broken.html")


def test_report_renders_in_headless_chromium_with_every_figure_loaded(tmp_path):
    path = _report(tmp_path).write(tmp_path / "report.html")
    if chromium_path() is None:
        sources = embedded_image_sources(path.read_text())
        assert sources and all(s.startswith("data:image/png;base64,") for s in sources)
        pytest.skip("chromium not installed (make chromium needs apt and root); checked "
                    "instead that every image is embedded PNG data")
    try:
        loaded, total = render_image_count(path)
    except ChromiumUnavailable as exc:
        pytest.skip(f"chromium did not render: {exc}")
    assert (loaded, total) == (3, 3)
    # The check can fail: a truncated PNG is counted as not loaded.
    assert render_image_count(_broken_page(tmp_path)) == (1, 2)


def test_user_text_is_escaped_in_every_place_of_a_document(tmp_path):
    """A ``<script>`` in any text of a document is shown, never run: no tag reaches the page."""
    attack = "<script>alert('x')</script>"
    (tmp_path / "figures").mkdir()
    (tmp_path / "figures" / "f.png").write_bytes(_png(2, 2))
    document = Document(attack, intro=[attack, Code(attack)])
    section = document.section(attack, level=3)
    section.paragraph([attack, Strong(attack), Verdict(attack, "fail")], tone="fail")
    section.bullets([attack, Link(attack, "sub/a b.json")])
    section.preformatted(attack)
    section.table([Column(attack, attack)], [[attack], [Code(attack)], [Verdict(attack, "warn")]],
                  caption=attack)
    section.figure("figures/f.png", attack, alt=attack)
    path = write_html(document, tmp_path / "report.html")
    page = path.read_text(encoding="utf-8")
    assert "<script" not in page
    escaped = html.escape(attack)
    # title and h1, intro twice, heading, paragraph three times, list item and link text, pre,
    # header (name and unit), caption, three cells, figure caption and alt
    assert page.count(escaped) == 19
    assert '<a href="sub/a b.json">' in page and '<td class="warn">' in page
    # the figure was read relative to the page's folder and embedded
    assert embedded_image_sources(page) == [png_data_uri(_png(2, 2))]


def _answering_report(tmp_path, rows=30):
    """A report as the studies write one: a summary, sections, a long table with a verdict
    column, figures."""
    document = Document("Study", intro="What was checked.")
    document.summarize([("passed", rows - 2, "pass"), ("warnings", 1, "warn"),
                        ("failed", 1, "fail")],
                       ["**check_7** failed: `kp` edge 0.9 below 1.0", "check_3: a warning"])
    checks = document.section("Checks")
    tones = ["fail" if i == 7 else "warn" if i == 3 else "pass" for i in range(rows)]
    checks.table(["check", Column("measured", "1", ".2f"), "verdict"],
                 [[f"check_{i}", i / 3, Verdict(tone, tone)] for i, tone in enumerate(tones)],
                 caption="Every check")
    document.section("Why", level=3).paragraph("Because `a` and **b**.")
    figures = document.section("Figures")
    figures.figure(_png(8, 8), "gain surface at 20 ms").figure(_png(6, 4), "step response")
    document.section("Limits").bullets(["linear model"])
    return write_html(document, tmp_path / "study.html"), document


def test_a_report_answers_first_in_a_browser(tmp_path):
    """Summary on top, every anchor resolving, every verdict cell classed and coloured, every
    image loaded; a screenshot of the first screen is kept beside the page."""
    from tests.support.html_render import inspect_report

    path, document = _answering_report(tmp_path)
    page = path.read_text(encoding="utf-8")
    assert "`" not in page and "**" not in page          # no raw markup reaches the reader
    assert "<code>kp</code>" in page and "<details><summary>Every check (30 rows" in page
    if chromium_path() is None:
        pytest.skip("chromium not installed (make chromium needs apt and root)")
    try:
        seen = inspect_report(path, screenshot=tmp_path / "study.png")
    except ChromiumUnavailable as exc:
        pytest.skip(f"chromium did not render: {exc}")
    assert seen["summary_top"] is not None and seen["summary_top"] < 250
    assert "28 passed" in seen["summary_text"] and "check_7 failed" in seen["summary_text"]
    assert seen["contents"] and seen["broken_anchors"] == []
    assert seen["anchors"] == len(document.table_of_contents()) == 4
    assert seen["verdict_cells"] == 30 and seen["unclassed_verdicts"] == []
    assert seen["images"] == [2, 2]
    assert (tmp_path / "study.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_browser_check_sees_a_broken_anchor_and_an_unclassed_verdict(tmp_path):
    from tests.support.html_render import inspect_report

    path, _ = _answering_report(tmp_path, rows=8)
    page = path.read_text(encoding="utf-8")
    page = page.replace('id="limits"', 'id="elsewhere"').replace(
        '<td class="warn">warn</td>', "<td>warn</td>")
    path.write_text(page, encoding="utf-8")
    if chromium_path() is None:
        pytest.skip("chromium not installed (make chromium needs apt and root)")
    seen = inspect_report(path)
    assert seen["broken_anchors"] == ["#limits"] and seen["unclassed_verdicts"] == ["warn"]

"""The HTML rendering of a report: one self-contained file, figures embedded, no outside links.

Renders a :class:`~orchestrator.report.document.Document` (the same one the Markdown is
rendered from). The page opens anywhere (mail attachment, CI artefact, a folder moved
elsewhere) with every figure in it and nothing fetched: figures are embedded as
``data:image/png;base64`` URIs, and a link may only name a file inside the report's folder.

Escaping policy: every string of the document is text and is HTML-escaped; markup is only
ever built here (:class:`_Raw` marks it, and never holds user text).

API
---
- :func:`render_html` ``(document, base_dir=None)``: the page as a string; a figure given as a
  relative path is read from ``base_dir`` (default: the working folder).
- :func:`write_html` ``(document, path)``: write the page atomically (figures read relative to
  the page's folder); returns the path.
- :class:`HtmlReport` ``(title, intro=None)``: a :class:`Document` with ``render()`` and
  ``write(path)``, for pages that have no Markdown twin (the FMU documentation).
- :func:`link` ``(text, relative_path)``: a :class:`~orchestrator.report.document.Link`
  (an absolute path, ``..`` or a URL with a scheme is refused).
- :func:`png_data_uri` ``(source, dpi=110)``: the ``data:`` URI of one figure.
- :func:`embedded_image_sources` ``(html)``: the ``src`` of every ``<img>`` (what the tests
  use to check that every image is embedded data).

Cells read as :func:`~orchestrator.report.document.cell` says; numbers are right-aligned and
a verdict cell carries its tone as its class (``<td class="pass">``), coloured by the page's
stylesheet. The page opens with the document's summary (``<section id="summary">``: counts by
verdict, headline findings) and a table of contents (``<nav id="contents">``) linking every
section's ``id``; a long table is a ``<details>`` element; figures are numbered.

Examples
--------
>>> report = HtmlReport("Wheel loop", intro="Sampled model, T = 20 ms.")
>>> section = report.section("Margins")
>>> _ = section.table([Column("kp"), Column("gain margin", "1", ".2f")], [[3.0, 4.512]])
>>> "4.51" in report.render()
True
"""

import base64
import html
import io
import re
from pathlib import Path, PurePath

from components.common.errors import ConfigError
from orchestrator.files.atomic import atomic_write_text

from .document import (CONTENTS_ANCHOR, SUMMARY_ANCHOR, Bullets, Code, Column, Document, Figure,
                       Link, Paragraph, Preformatted, Section, Strong, Table, Verdict, cell,
                       inline_parts)

__all__ = ["HtmlReport", "Section", "Column", "embedded_image_sources", "link", "png_data_uri",
           "render_html", "write_html"]

_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 70rem; margin: 2rem auto;
       padding: 0 1rem; color: #222; line-height: 1.45; }
h1 { border-bottom: 2px solid #444; padding-bottom: .3rem; }
h2 { border-bottom: 1px solid #bbb; margin-top: 2.2rem; }
table { border-collapse: collapse; margin: .8rem 0; font-size: .92rem; }
th, td { border: 1px solid #bbb; padding: .25rem .55rem; text-align: left;
         vertical-align: top; }
th { background: #eee; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
caption { caption-side: top; text-align: left; font-weight: 600; padding: .3rem 0; }
figure { margin: 1rem 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: .9rem; color: #444; }
pre { background: #f5f5f5; padding: .6rem; overflow-x: auto; }
code { font-size: .95em; background: #f3f3f3; padding: 0 .2em; border-radius: 3px; }
.pass { color: #176317; font-weight: 600; }
.fail { color: #a31515; font-weight: 600; }
.warn { color: #8a5a00; font-weight: 600; }
td.pass { background: #e7f4e7; }
td.fail { background: #fbe6e6; }
td.warn { background: #fdf3dc; }
.summary { border: 2px solid #444; border-radius: 6px; padding: .2rem 1rem .6rem;
           background: #fafafa; }
.summary h2 { border: none; margin-top: .6rem; }
.counts span { display: inline-block; margin-right: 1.2rem; font-size: 1.1rem; }
nav.toc ol { margin: .2rem 0; }
details { margin: .8rem 0; }
details > summary { cursor: pointer; font-weight: 600; }
"""


class _Raw(str):
    """Markup built by this module (already escaped); never user text."""


def link(text, relative_path):
    """A link to a file beside the report, for a table cell, a list item or a paragraph.

    Parameters
    ----------
    text : str
        Link text (escaped).
    relative_path : str or Path
        Path relative to the report's folder; absolute paths, ``..`` and URLs are refused.

    Returns
    -------
    Link

    Raises
    ------
    ConfigError
        If the target is absolute, leaves the folder or has a URL scheme.
    """
    return Link(str(text), relative_path)


def png_data_uri(source, dpi=110):
    """The ``data:image/png;base64,...`` URI of a figure.

    Parameters
    ----------
    source : str, Path, bytes or matplotlib.figure.Figure
        A PNG file, PNG bytes, or a figure (rendered to PNG in memory).
    dpi : int, optional
        Resolution for a matplotlib figure.

    Returns
    -------
    str

    Raises
    ------
    ConfigError
        If the file is missing or the data is not a PNG.
    """
    if hasattr(source, "savefig"):
        buffer = io.BytesIO()
        source.savefig(buffer, format="png", dpi=dpi)
        data = buffer.getvalue()
        name = "matplotlib figure"
    elif isinstance(source, (bytes, bytearray)):
        data, name = bytes(source), "PNG bytes"
    else:
        path = Path(source)
        if not path.is_file():
            raise ConfigError(f"HTML report figure {path}: file not found")
        data, name = path.read_bytes(), str(path)
    if not data.startswith(_PNG_MAGIC):
        raise ConfigError(f"HTML report figure {name}: not a PNG image")
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def embedded_image_sources(page):
    """The ``src`` attribute of every ``<img>`` in an HTML page, in order.

    Parameters
    ----------
    page : str

    Returns
    -------
    list of str
    """
    return re.findall(r"<img\b[^>]*\bsrc=\"([^\"]*)\"", page)


def _inline(content):
    """Markup of inline content: text escaped, each inline kind its element."""
    out = []
    for part in inline_parts(content):
        if isinstance(part, str):
            out.append(html.escape(part))
        elif isinstance(part, Code):
            out.append(f"<code>{html.escape(part.text)}</code>")
        elif isinstance(part, Strong):
            out.append(f"<strong>{html.escape(part.text)}</strong>")
        elif isinstance(part, Verdict):
            out.append(f'<span class="{part.tone}">{html.escape(part.text)}</span>')
        else:
            out.append(f'<a href="{html.escape(part.target, quote=True)}">'
                       f"{html.escape(part.text)}</a>")
    return _Raw("".join(out))


def _cell(value, column):
    """``<td>`` of one value: numbers right-aligned, a verdict in its tone, text left."""
    content, number = cell(value, column)
    if isinstance(content, Verdict):
        return f'<td class="{content.tone}">{html.escape(content.text)}</td>'
    attribute = ' class="num"' if number else ""
    return f"<td{attribute}>{_inline(content)}</td>"


def _table(table):
    parts = ["<table>"]
    if table.caption:
        parts.append(f"<caption>{_inline(table.caption)}</caption>")
    parts.append("<thead><tr>" + "".join(f"<th>{html.escape(c.header)}</th>"
                                         for c in table.columns) + "</tr></thead><tbody>")
    for row in table.rows:
        parts.append("<tr>" + "".join(_cell(v, c) for v, c in zip(row, table.columns))
                     + "</tr>")
    parts.append("</tbody></table>")
    if table.collapsed:
        what = _inline(table.caption) if table.caption else "Table"
        return (f"<details><summary>{what} ({len(table.rows)} rows; click to open)</summary>"
                + "".join(parts) + "</details>")
    return "".join(parts)


def _figure(figure, base_dir, number):
    source = figure.source
    if isinstance(source, (str, PurePath)) and base_dir is not None \
            and not Path(source).is_absolute():
        source = Path(base_dir) / source
    uri = png_data_uri(source, dpi=figure.dpi)
    alt_text = html.escape(figure.alt or figure.caption, quote=True)
    return (f'<figure id="figure-{number}"><img src="{uri}" alt="{alt_text}">'
            f"<figcaption>Figure {number}. {_inline(figure.caption)}</figcaption></figure>")


def _block(block, base_dir, figures):
    if isinstance(block, Paragraph):
        attribute = f' class="{block.tone}"' if block.tone else ""
        return f"<p{attribute}>{_inline(block.content)}</p>"
    if isinstance(block, Bullets):
        return "<ul>" + "".join(f"<li>{_inline(item)}</li>" for item in block.items) + "</ul>"
    if isinstance(block, Preformatted):
        return f"<pre>{html.escape(block.text)}</pre>"
    if isinstance(block, Table):
        return _table(block)
    if isinstance(block, Figure):
        figures.append(block)
        return _figure(block, base_dir, len(figures))
    raise ConfigError(f"HTML report: unknown block {block!r}")


def _section(section, base_dir, figures):
    tag = f"h{section.level}"
    return (f'<section id="{html.escape(section.anchor, quote=True)}"><{tag}>'
            f"{html.escape(section.heading)}</{tag}>"
            + "".join(_block(b, base_dir, figures) for b in section.blocks) + "</section>")


def _summary(summary):
    """The summary box: counts by verdict, then the findings."""
    if summary is None:
        return ""
    counts = "".join(f'<span class="{tone}">{count} {html.escape(label)}</span>'
                     for label, count, tone in summary.counts)
    findings = ("<ul>" + "".join(f"<li>{_inline(item)}</li>" for item in summary.findings)
                + "</ul>") if summary.findings else ""
    return (f'<section id="{SUMMARY_ANCHOR}" class="summary"><h2>Summary</h2>'
            f'<p class="counts">{counts}</p>{findings}</section>')


def _contents(document):
    """The table of contents: the sections of level 2, each with its level-3 sections."""
    listed = document.table_of_contents()
    if not listed:
        return ""
    tree = []   # (heading, anchor, children)
    for level, heading, anchor in listed:
        if level == 2 or not tree:
            tree.append((heading, anchor, []))
        else:
            tree[-1][2].append((heading, anchor, []))

    def items(nodes):
        return "<ol>" + "".join(
            f'<li><a href="#{html.escape(anchor, quote=True)}">{html.escape(heading)}</a>'
            + (items(children) if children else "") + "</li>"
            for heading, anchor, children in nodes) + "</ol>"

    return f'<nav id="{CONTENTS_ANCHOR}" class="toc"><h2>Contents</h2>{items(tree)}</nav>'


def render_html(document, base_dir=None):
    """The whole page of ``document`` as a string.

    Parameters
    ----------
    document : Document
    base_dir : path-like, optional
        Folder that figures given as relative paths are read from (default: the working
        folder).

    Returns
    -------
    str
    """
    intro = f"<p>{_inline(document.intro)}</p>" if document.intro else ""
    figures = []
    body = (_summary(document.summary) + _contents(document)
            + "".join(_section(section, base_dir, figures) for section in document.sections))
    title = html.escape(document.title)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{title}</title><style>{_STYLE}</style></head>"
            f"<body><h1>{title}</h1>{intro}{body}</body></html>\n")


def write_html(document, path):
    """Write the page (UTF-8) atomically: a reader never sees a half-written file.

    Parameters
    ----------
    document : Document
    path : str or Path
        The page; its folder is created, and figures given as relative paths are read from it.

    Returns
    -------
    Path
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, render_html(document, base_dir=path.parent), fsync=False)
    return path


class HtmlReport(Document):
    """A :class:`Document` rendered only to HTML (see the module docstring).

    Parameters
    ----------
    title : str
    intro : str, optional
        A lead paragraph under the title.
    """

    def render(self):
        """The whole page as a string (relative figure paths read from the working folder)."""
        return render_html(self)

    def write(self, path):
        """Write the page atomically (see :func:`write_html`); returns the path."""
        return write_html(self, path)

"""The Markdown rendering of a report (GitHub-flavoured), figures linked relatively.

Renders the same :class:`~orchestrator.report.document.Document` as
:mod:`~orchestrator.report.html`, block for block: the summary (``## Summary``: counts by
verdict in bold, the findings as a list) and a table of contents (``## Contents``, links to
the headings' anchors, which :func:`~orchestrator.report.document.slug` makes the same as
GitHub's) come first; a section is a ``##``..``####`` heading, a table a pipe table with its
caption in italics above (a long one inside ``<details>``), a figure ``![alt](path)`` with
its numbered caption below, a verdict in bold. Cells read as
:func:`~orchestrator.report.document.cell` says, the same text as in the HTML.

Escaping policy: strings are text, never markup. A ``<`` that would open an HTML tag and an
``&`` that would start an entity are written as entities, a ``|`` in a table cell as ``\\|``,
and a line break inside a cell or a list item as a space. Links and figures name files
inside the report's folder only (:func:`~orchestrator.report.document.relative_target`), their
paths percent-encoded (a space is ``%20``).

Examples
--------
>>> from orchestrator.report.document import Column, Document, Verdict
>>> document = Document("Wheel loop")
>>> _ = document.section("Checks").table(["check", Column("margin", "dB", ".1f"), "verdict"],
...                                      [["gain <b>margin</b>", 12.04, Verdict("pass", "pass")]])
>>> print(render_markdown(document))
# Wheel loop
<BLANKLINE>
## Checks
<BLANKLINE>
| check | margin [dB] | verdict |
|---|---|---|
| gain &lt;b>margin&lt;/b> | 12.0 | **pass** |
<BLANKLINE>
"""

import re
from pathlib import Path
from urllib.parse import quote

from orchestrator.files.atomic import atomic_write_text

from .document import (CONTENTS_ANCHOR, SUMMARY_ANCHOR, Bullets, Code, Figure, Link, Paragraph,
                       Preformatted, Strong, Table, Verdict, cell, inline_parts)

__all__ = ["render_markdown", "write_markdown"]

_TAG_START = re.compile(r"<(?=[A-Za-z/!?])")
_ENTITY_START = re.compile(r"&(?=#?[A-Za-z0-9]+;)")


def _text(text):
    return _TAG_START.sub("&lt;", _ENTITY_START.sub("&amp;", text))


def _code(text):
    fence = "`" * (max((len(run) for run in re.findall(r"`+", text)), default=0) + 1)
    padding = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{padding}{text}{padding}{fence}"


def _inline(content):
    out = []
    for part in inline_parts(content):
        if isinstance(part, str):
            out.append(_text(part))
        elif isinstance(part, Code):
            out.append(_code(part.text))
        elif isinstance(part, (Strong, Verdict)):
            out.append(f"**{_text(part.text)}**")
        elif isinstance(part, Link):
            out.append(f"[{_text(part.text)}]({quote(part.target)})")
    return "".join(out)


def _one_line(text):
    return " ".join(text.splitlines())


def _row(cells):
    return "| " + " | ".join(_one_line(c).replace("|", "\\|") for c in cells) + " |"


def _table(table):
    caption = _one_line(_inline(table.caption)) if table.caption else ""
    lines = [f"*{caption}*", ""] if caption and not table.collapsed else []
    lines.append(_row([_text(c.header) for c in table.columns]))
    lines.append("|" + "|".join("---" for _ in table.columns) + "|")
    for values in table.rows:
        lines.append(_row([_inline(cell(v, c)[0]) for v, c in zip(values, table.columns)]))
    if table.collapsed:   # GitHub shows the summary line and opens the rows on a click
        what = caption or "Table"
        return (f"<details><summary>{what} ({len(table.rows)} rows; click to open)</summary>"
                "\n\n" + "\n".join(lines) + "\n\n</details>")
    return "\n".join(lines)


def _block(block, figures):
    if isinstance(block, Paragraph):
        return _inline(block.content)
    if isinstance(block, Bullets):
        return "\n".join(f"- {_one_line(_inline(item))}" for item in block.items)
    if isinstance(block, Preformatted):
        fence = "`" * max(3, max((len(r) for r in re.findall(r"`+", block.text)), default=0) + 1)
        return f"{fence}\n{block.text.rstrip(chr(10))}\n{fence}"
    if isinstance(block, Table):
        return _table(block)
    if isinstance(block, Figure):
        figures.append(block)
        caption = _one_line(_inline(block.caption))
        alt = _one_line(block.alt or block.caption).replace("]", "\\]")
        return (f"![{_text(alt)}]({quote(block.link_target())})\n\n"
                f"*Figure {len(figures)}. {caption}*")
    raise TypeError(f"Markdown report: unknown block {block!r}")


def render_markdown(document, html_companion=None):
    """The Markdown text of ``document``.

    Parameters
    ----------
    document : Document
    html_companion : str, optional
        File name of the HTML rendering beside it; the lead then points to it.

    Returns
    -------
    str
        Blocks separated by blank lines, ending with a newline.
    """
    chunks = [f"# {_text(document.title)}"]
    lead = _inline(document.intro) if document.intro else ""
    if html_companion:
        target = Link(html_companion, html_companion)
        lead += (" " if lead else "") + ("Self-contained version with the figures embedded: "
                                          f"{_inline(target)}.")
    if lead:
        chunks.append(lead)
    chunks += _summary(document.summary) + _contents(document)
    figures = []
    for section in document.sections:
        chunks.append(f"{'#' * section.level} {_text(section.heading)}")
        chunks += [_block(block, figures) for block in section.blocks]
    return "\n\n".join(chunks) + "\n"


def _summary(summary):
    if summary is None:
        return []
    counts = " \u00b7 ".join(f"**{count} {_text(label)}**" for label, count, _ in summary.counts)
    chunks = ["## Summary", counts]   # the heading's anchor is SUMMARY_ANCHOR
    if summary.findings:
        chunks.append("\n".join(f"- {_one_line(_inline(item))}" for item in summary.findings))
    return chunks


def _contents(document):
    listed = document.table_of_contents()
    if not listed:
        return []
    lines = [f"{'  ' * (level - 2)}- [{_text(heading)}](#{anchor})"
             for level, heading, anchor in listed]
    return ["## Contents", "\n".join(lines)]   # anchor: CONTENTS_ANCHOR


def write_markdown(document, path, html_companion=None):
    """Write :func:`render_markdown` atomically; returns the path.

    Parameters
    ----------
    document : Document
    path : str or Path
        Figures are linked relative to its folder.
    html_companion : str, optional
        See :func:`render_markdown`.

    Returns
    -------
    Path
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, render_markdown(document, html_companion), fsync=False)
    return path

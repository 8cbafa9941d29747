"""Markdown written for the repository, read into a report document (the other direction of
:mod:`~orchestrator.report.markdown`).

The FMU documentation pages include the models' pages of ``docs/``; shown as text they read as
raw Markdown. :func:`add_markdown` reads the subset those pages use into
:class:`~orchestrator.report.document.Document` blocks, so either rendering shows headings,
paragraphs, lists, tables and code as such:

- ``#`` .. ``####`` headings start sections (one level below ``level``; deeper ones stay at 4);
- blank-line separated paragraphs, their lines joined;
- ``-``, ``*`` and ``1.`` list items (indented continuation lines joined);
- fenced code blocks, kept as they are;
- pipe tables (header, ``---`` separator, rows);
- inline code and ``**strong**`` (the document's own reading of text); a link
  ``[text](target)`` keeps its text only and an image its alternative text, because the page
  that includes them does not carry the files they name.

Examples
--------
>>> from orchestrator.report.document import Document
>>> document = Document("Plant")
>>> add_markdown(document, "# Motor\\n\\nThe `R` of\\nthe motor.\\n\\n- one\\n- two\\n")
>>> [(s.heading, [type(b).__name__ for b in s.blocks]) for s in document.sections]
[('Motor', ['Paragraph', 'Bullets'])]
>>> document.sections[0].blocks[0].content
('The ', Code(text='R'), ' of the motor.')
"""

import re

__all__ = ["add_markdown"]

_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_ITEM = re.compile(r"^\s*(?:[-*]|\d+[.)])\s+(.*)$")
_FENCE = re.compile(r"^\s*(```+|~~~+)")
_LINK = re.compile(r"!?\[([^\]]*)\]\([^)]*\)")
_SEPARATOR = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _text(line):
    """A line of Markdown prose as document text: links and images as their text."""
    return _LINK.sub(lambda match: match.group(1), line)


def _heading(text):
    """A heading as plain text (a heading is not inline content): no code or strong marks."""
    return _text(text).replace("`", "").replace("**", "")


def _cells(line):
    """A table row's cells, split at ``|`` outside code spans (``|x|`` in code is a norm)."""
    cells, current, in_code = [], [], False
    for char in line.strip().strip("|"):
        if char == "`":
            in_code = not in_code
        if char == "|" and not in_code:
            cells.append("".join(current))
            current = []
        else:
            current.append(char)
    cells.append("".join(current))
    return [_text(cell.strip()) for cell in cells]


def add_markdown(document, text, level=2, section=None):
    """Append the blocks of Markdown ``text`` to ``document``.

    Parameters
    ----------
    document : Document
    text : str
        The Markdown.
    level : int
        The level of the section the text belongs under: its ``#`` headings become sections
        of ``level + 1`` (``##`` of ``level + 2``, at most 4).
    section : Section, optional
        Where blocks before the first heading go (default: a new section named after the
        document's title).
    """
    lines = text.splitlines()
    current, index = section, 0

    def target():
        nonlocal current
        if current is None:
            current = document.section(document.title, min(level + 1, 4))
        return current

    while index < len(lines):
        line = lines[index]
        heading = _HEADING.match(line)
        fence = _FENCE.match(line)
        if not line.strip():
            index += 1
        elif heading:
            depth = len(heading.group(1))
            current = document.section(_heading(heading.group(2)), min(level + depth, 4))
            index += 1
        elif fence:
            end = index + 1
            while end < len(lines) and not lines[end].strip().startswith(fence.group(1)):
                end += 1
            target().preformatted("\n".join(lines[index + 1:end]))
            index = end + 1
        elif line.lstrip().startswith("|") and index + 1 < len(lines) \
                and _SEPARATOR.match(lines[index + 1]):
            header = [_heading(cell) for cell in _cells(line)]   # headers are plain text
            end = index + 2
            rows = []
            while end < len(lines) and lines[end].lstrip().startswith("|"):
                row = _cells(lines[end])
                rows.append((row + [""] * len(header))[:len(header)])
                end += 1
            target().table(header, rows, collapsed=False)
            index = end
        elif _ITEM.match(line):
            items = []
            while index < len(lines) and lines[index].strip():
                item = _ITEM.match(lines[index])
                if item:
                    items.append(_text(item.group(1)))
                elif items:   # a continuation line of the item above
                    items[-1] += " " + _text(lines[index].strip())
                index += 1
            target().bullets(items)
        else:   # the first line always belongs to it, whatever it starts with
            paragraph = [_text(line.strip())]
            index += 1
            while index < len(lines) and lines[index].strip() and not (
                    _HEADING.match(lines[index]) or _FENCE.match(lines[index])
                    or _ITEM.match(lines[index]) or lines[index].lstrip().startswith("|")):
                paragraph.append(_text(lines[index].strip()))
                index += 1
            target().paragraph(" ".join(paragraph))

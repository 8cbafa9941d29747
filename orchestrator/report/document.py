"""A report as data: title, lead and sections of blocks, written once, rendered twice.

A study builds one :class:`Document`; :mod:`~orchestrator.report.markdown` and
:mod:`~orchestrator.report.html` render that same document, so the two texts cannot drift.
Nothing here knows either output format.

Model
-----
- :class:`Document` ``(title, intro=None)``; ``document.section(heading, level=2)`` appends
  and returns a :class:`Section` with a unique :attr:`Section.anchor` (GitHub's heading slug,
  so the Markdown's links resolve too); ``document.summarize(counts, findings)`` sets the
  :class:`Summary` both renderings open with (the answer first), before a table of contents.
- :class:`Section` holds blocks in order; each adder returns the section, so calls chain:
  ``paragraph(content, tone=None)``, ``bullets(items)``, ``preformatted(text)``,
  ``table(columns, rows, caption=None)``, ``figure(source, caption, alt=None, dpi=110)``.
- Blocks: :class:`Paragraph`, :class:`Bullets`, :class:`Preformatted`, :class:`Table` (of
  :class:`Column`; one longer than :data:`LONG_TABLE_ROWS` rows is rendered collapsed unless
  told otherwise), :class:`Figure` (numbered in order by the renderings).
- Inline content (a paragraph, a list item, a table cell, a caption): a string, one of
  :class:`Code`, :class:`Strong`, :class:`Verdict`, :class:`Link`, or a list of those. Strings
  are text, never markup, in every rendering, with one reading rule so that text written for
  people never shows raw markup: a span in backticks is :class:`Code` and a span in double
  asterisks is :class:`Strong` (:func:`inline_parts`).

Cells (:func:`cell`): None and NaN read as an em dash, booleans as "yes"/"no", floats through
the column's format (default ``.4g``), integers through it when it has one, inline content as
itself, anything else through ``str``.

Examples
--------
>>> document = Document("Wheel loop")
>>> _ = document.section("Checks").table(
...     [Column("check"), Column("margin", "dB", ".1f"), Column("verdict")],
...     [["gain_margin", 12.04, Verdict("pass", "pass")]])
>>> table = document.sections[0].blocks[0]
>>> [cell(v, c)[0] for v, c in zip(table.rows[0], table.columns)]
['gain_margin', '12.0', Verdict(text='pass', tone='pass')]
"""

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import PurePath, PurePosixPath

from components.common.errors import ConfigError

__all__ = ["Bullets", "Code", "Column", "Document", "EMPTY_CELL", "Figure", "LONG_TABLE_ROWS",
           "Link", "Paragraph", "Preformatted", "Section", "Strong", "Summary", "TONES", "Table",
           "Verdict", "cell", "inline_parts", "relative_target", "slug"]

EMPTY_CELL = "\u2014"
TONES = ("pass", "fail", "warn")
# Rows above which a table is rendered collapsed (about one screen at 1280 px wide).
LONG_TABLE_ROWS = 20
_MARKUP = re.compile(r"`([^`\n]+)`|\*\*([^*\n]+)\*\*")


def slug(text):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.

    Examples
    --------
    >>> slug("Claims and verdicts: 95 % interval")
    'claims-and-verdicts-95--interval'
    """
    return re.sub(r"[^\w\- ]", "", text.strip().lower()).replace(" ", "-")


def relative_target(target, what):
    """``target`` as a POSIX path relative to the report's folder, or ConfigError.

    The written files must not point outside their folder or to the network: an absolute
    path, ``..`` or a URL scheme is refused (``what`` names the link or figure).
    """
    text = str(target).replace(os.sep, "/")
    posix = PurePosixPath(text)
    if (not text or posix.is_absolute() or re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", text)
            or ".." in posix.parts):
        raise ConfigError(f"{what} {text!r}: must be a relative path inside the report's "
                          "folder (no absolute path, no '..', no URL)")
    return text


@dataclass(frozen=True)
class Code:
    """Inline code: a file, a command, a name (monospace)."""

    text: str


@dataclass(frozen=True)
class Strong:
    """Emphasised text."""

    text: str


@dataclass(frozen=True)
class Verdict:
    """A verdict's word, shown by its tone: ``pass``, ``fail`` or ``warn``."""

    text: str
    tone: str

    def __post_init__(self):
        if self.tone not in TONES:
            raise ConfigError(f"report verdict {self.text!r}: tone = {self.tone!r}, valid: "
                              f"{', '.join(TONES)}")


@dataclass(frozen=True)
class Link:
    """A link to a file beside the report (see :func:`relative_target`)."""

    text: str
    target: str

    def __post_init__(self):
        object.__setattr__(self, "target", relative_target(self.target, "report link"))


_INLINE = (str, Code, Strong, Verdict, Link)


def _read_markup(text):
    """A string as text, code and strong parts (see the module docstring)."""
    parts, start = [], 0
    for match in _MARKUP.finditer(text):
        if match.start() > start:
            parts.append(text[start:match.start()])
        # **`name`** reads as a strong name: the code marks inside are dropped
        parts.append(Code(match.group(1)) if match.group(1) is not None
                     else Strong(match.group(2).replace("`", "")))
        start = match.end()
    if start < len(text):
        parts.append(text[start:])
    return parts


def inline_parts(content):
    """Inline content as a tuple of strings and inline objects.

    A string's spans in backticks become :class:`Code`, in double asterisks :class:`Strong`.

    Examples
    --------
    >>> inline_parts("set `v_cruise` **now**")
    ('set ', Code(text='v_cruise'), ' ', Strong(text='now'))

    Raises
    ------
    ConfigError
        For anything that is not inline content.
    """
    if isinstance(content, _INLINE):
        content = (content,)
    if isinstance(content, (list, tuple)):
        parts = tuple(content)
        bad = [p for p in parts if not isinstance(p, _INLINE)]
        if not bad:
            return tuple(piece for part in parts for piece in
                         (_read_markup(part) if isinstance(part, str)
                          and ("`" in part or "**" in part) else (part,)))
        content = bad[0]
    raise ConfigError(f"report text {content!r}: not text ({type(content).__name__}); "
                      "valid: str, Code, Strong, Verdict, Link or a list of them")


@dataclass(frozen=True)
class Column:
    """A table column: name, unit (shown as ``name [unit]``) and number format.

    Parameters
    ----------
    name : str
    unit : str, optional
        SI unit or "1" for a dimensionless number; None shows no brackets.
    format : str, optional
        :func:`format` spec for floats, e.g. ``".3f"``; default ``".4g"``.
    """

    name: str
    unit: str = None
    format: str = None

    @property
    def header(self):
        """The header text, ``name [unit]`` or ``name``."""
        return self.name if self.unit is None else f"{self.name} [{self.unit}]"


def cell(value, column):
    """How one table cell reads: ``(content, is_number)``; see the module docstring.

    ``content`` is text or inline content; ``is_number`` tells a renderer to align it right.
    """
    if isinstance(value, (Code, Strong, Verdict, Link, list, tuple)):
        return value, False
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return EMPTY_CELL, True
    kind = getattr(getattr(value, "dtype", None), "kind", "")   # numpy scalars
    if isinstance(value, bool) or kind == "b":
        return ("yes" if value else "no"), False
    if isinstance(value, float) or kind == "f":
        value = float(value)
        return (EMPTY_CELL if math.isnan(value) else format(value, column.format or ".4g")), True
    if isinstance(value, int) or kind in ("i", "u"):
        return (format(value, column.format) if column.format else str(value)), True
    return str(value), False


@dataclass
class Paragraph:
    """Inline content; ``tone`` (pass, fail, warn) colours it where the output can."""

    content: object
    tone: str = None

    def __post_init__(self):
        self.content = inline_parts(self.content)
        if self.tone is not None and self.tone not in TONES:
            raise ConfigError(f"report paragraph: tone = {self.tone!r}, valid: "
                              f"{', '.join(TONES)}")


@dataclass
class Bullets:
    """An unordered list; each item is inline content."""

    items: list

    def __post_init__(self):
        self.items = [inline_parts(item) for item in self.items]


@dataclass
class Preformatted:
    """Text shown as it is, in a monospace block."""

    text: str


@dataclass
class Table:
    """Columns and rows of cells, with an optional caption above.

    ``collapsed``: render it folded (a ``<details>`` element: the caption and the row count
    show, the rows open on a click); default when it has more than :data:`LONG_TABLE_ROWS`
    rows.
    """

    columns: list
    rows: list
    caption: str = None
    collapsed: bool = None

    def __post_init__(self):
        self.columns = [c if isinstance(c, Column) else Column(str(c)) for c in self.columns]
        self.rows = [list(row) for row in self.rows]
        for index, row in enumerate(self.rows):
            if len(row) != len(self.columns):
                raise ConfigError(f"report table {self.caption!r}: row {index} has {len(row)} "
                                  f"cells for {len(self.columns)} columns")
        if self.collapsed is None:
            self.collapsed = len(self.rows) > LONG_TABLE_ROWS


@dataclass
class Figure:
    """A PNG figure with its caption.

    ``source`` is a path relative to the report's folder (the Markdown links it, the HTML
    embeds it), or, for HTML only, an absolute path, PNG bytes or a matplotlib figure.
    """

    source: object
    caption: str
    alt: str = None
    dpi: int = 110

    def link_target(self):
        """The relative path the Markdown links (ConfigError if the figure has none)."""
        if not isinstance(self.source, (str, PurePath)):
            raise ConfigError(f"report figure {self.caption!r}: has no file to link; give "
                              "the PNG's path relative to the report")
        return relative_target(self.source, f"report figure {self.caption!r}:")


@dataclass
class Section:
    """A heading (level 2 to 4) and its blocks; built through :meth:`Document.section`.

    ``anchor`` is the heading's id, unique in its document (``#anchor`` links to it).
    """

    heading: str
    level: int = 2
    blocks: list = field(default_factory=list)
    anchor: str = None

    def __post_init__(self):
        if self.level not in (2, 3, 4):
            raise ConfigError(f"report section {self.heading!r}: level = {self.level!r}, "
                              "valid 2, 3, 4")

    def add(self, block):
        """Append a block; returns the section."""
        self.blocks.append(block)
        return self

    def paragraph(self, content, tone=None):
        """Add a :class:`Paragraph`."""
        return self.add(Paragraph(content, tone))

    def bullets(self, items):
        """Add :class:`Bullets`."""
        return self.add(Bullets(list(items)))

    def preformatted(self, text):
        """Add :class:`Preformatted` text."""
        return self.add(Preformatted(str(text)))

    def table(self, columns, rows, caption=None, collapsed=None):
        """Add a :class:`Table`; a string column is a column without unit."""
        return self.add(Table(columns, rows, caption if caption else None, collapsed))

    def figure(self, source, caption, alt=None, dpi=110):
        """Add a :class:`Figure`."""
        return self.add(Figure(source, caption, alt, dpi))


@dataclass
class Summary:
    """The answer a report opens with: counts by verdict, then the headline findings.

    Parameters
    ----------
    counts : list of (str, int, str)
        ``(label, count, tone)`` per verdict, e.g. ``("passed", 19, "pass")``.
    findings : list of inline content
        One line each: what a reader must know first.
    """

    counts: list
    findings: list = field(default_factory=list)

    def __post_init__(self):
        self.counts = [(str(label), int(count), tone) for label, count, tone in self.counts]
        for label, _, tone in self.counts:
            if tone not in TONES:
                raise ConfigError(f"report summary count {label!r}: tone = {tone!r}, valid: "
                                  f"{', '.join(TONES)}")
        self.findings = [inline_parts(item) for item in self.findings]


# Anchors the renderings give the summary and the table of contents.
SUMMARY_ANCHOR, CONTENTS_ANCHOR = "summary", "contents"


class Document:
    """A report: title, optional lead paragraph, an optional summary, sections in order.

    Parameters
    ----------
    title : str
    intro : inline content, optional
    contents : bool
        Whether the renderings list the sections (levels 2 and 3) after the summary, each
        linked to its anchor; only a document of more than two sections gets one.
    """

    def __init__(self, title, intro=None, contents=True):
        self.title = title
        self.intro = inline_parts(intro) if intro else None
        self.sections = []
        self.summary = None
        self.contents = contents
        self._anchors = {SUMMARY_ANCHOR, CONTENTS_ANCHOR}

    def section(self, heading, level=2):
        """Append and return a new :class:`Section` with a unique anchor."""
        base = slug(heading) or "section"
        anchor, number = base, 0
        while anchor in self._anchors:   # GitHub numbers repeated headings the same way
            number += 1
            anchor = f"{base}-{number}"
        self._anchors.add(anchor)
        section = Section(heading, level, anchor=anchor)
        self.sections.append(section)
        return section

    def summarize(self, counts, findings=()):
        """Set the :class:`Summary` the renderings open with; returns it."""
        self.summary = Summary(list(counts), list(findings))
        return self.summary

    def table_of_contents(self):
        """``[(level, heading, anchor), ...]`` of the sections a table of contents lists
        (empty when there is none to show)."""
        listed = [(s.level, s.heading, s.anchor) for s in self.sections if s.level <= 3]
        return listed if self.contents and len(self.sections) > 2 else []

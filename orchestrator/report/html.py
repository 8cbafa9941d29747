"""Self-contained HTML reports: one file, figures embedded, no network links, no absolute paths.

Shared by ``sonotrack verify`` and ``sonotrack reproduce``. A report is a title, an optional
lead paragraph and a list of sections; each section holds blocks in order: paragraphs,
tables, figures, preformatted text or a list. Every string is HTML-escaped; figures are
embedded as ``data:image/png;base64`` URIs, so the page opens anywhere (mail attachment,
CI artefact, a folder moved elsewhere) with every figure in it and nothing fetched.

API
---
- :class:`HtmlReport` ``(title, intro=None)``; ``report.section(heading, level=2)`` returns a
  :class:`Section`; ``report.write(path)`` writes the page atomically and returns the path;
  ``report.render()`` returns the page as a string.
- :class:`Section` methods, each returns the section (so calls chain):
  ``paragraph(text)``, ``bullets(items)``, ``preformatted(text)``,
  ``table(columns, rows, caption=None)``, ``figure(source, caption, alt=None, dpi=110)``.
  ``source`` is a PNG file path, PNG bytes, or a matplotlib ``Figure`` (saved to PNG in
  memory at ``dpi``; the figure is not closed).
- :class:`Column` ``(name, unit=None, format=None)``: a table header with its unit, shown
  as ``name [unit]``; ``format`` is a :func:`format` spec for numbers (e.g. ``".3f"``).
  A plain string is accepted as a column without unit.
- :func:`png_data_uri` ``(source, dpi=110)``: the ``data:`` URI of one figure.
- :func:`embedded_image_sources` ``(html)``: the ``src`` of every ``<img>`` (what the tests
  use to check that every image is embedded data).

Cells: ``None`` and NaN print as an em dash, booleans as "yes"/"no", floats through the
column's format (default ``.4g``), anything else through ``str``. Text is never
interpreted as HTML; a link to a file next to the report is ``link(text, relative_path)``
(an absolute path or a URL with a scheme is refused: the page must not point outside its
folder or to the network).

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
import math
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from components.common.errors import ConfigError

__all__ = ["HtmlReport", "Section", "Column", "png_data_uri", "embedded_image_sources",
           "link"]

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
.pass { color: #176317; font-weight: 600; }
.fail { color: #a31515; font-weight: 600; }
.warn { color: #8a5a00; font-weight: 600; }
"""


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


class _Raw(str):
    """Markup built by this module (already escaped); never user text."""


def link(text, relative_path):
    """An ``<a>`` to a file beside the report, for use as a table cell or in ``bullets``.

    Parameters
    ----------
    text : str
        Link text (escaped).
    relative_path : str or Path
        Path relative to the report's folder; absolute paths, ``..`` and URLs are refused.

    Returns
    -------
    str
        Markup that :class:`Section` inserts as is.

    Raises
    ------
    ConfigError
        If the target is absolute, leaves the folder or has a URL scheme.
    """
    target = str(relative_path).replace(os.sep, "/")
    posix = PurePosixPath(target)
    if (posix.is_absolute() or re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", target)
            or ".." in posix.parts):
        raise ConfigError(f"HTML report link {target!r}: must be a relative path inside the "
                          "report's folder (no absolute path, no '..', no URL)")
    return _Raw(f'<a href="{html.escape(target, quote=True)}">{html.escape(str(text))}</a>')


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _text(value):
    return value if isinstance(value, _Raw) else html.escape(str(value))


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


def _cell(value, column):
    """``<td>`` of one value: numbers right-aligned, text left (see the module docstring)."""
    if isinstance(value, _Raw):
        return f"<td>{value}</td>"
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "<td class=\"num\">\u2014</td>"
    if isinstance(value, bool):
        return f"<td>{'yes' if value else 'no'}</td>"
    if isinstance(value, float) or (hasattr(value, "dtype") and value.dtype.kind == "f"):
        return f"<td class=\"num\">{html.escape(format(float(value), column.format or '.4g'))}</td>"
    if isinstance(value, int):
        text = format(value, column.format) if column.format else str(value)
        return f"<td class=\"num\">{html.escape(text)}</td>"
    return f"<td>{html.escape(str(value))}</td>"


class Section:
    """A heading and its blocks; built through :meth:`HtmlReport.section`."""

    def __init__(self, heading, level=2):
        if level not in (2, 3, 4):
            raise ConfigError(f"HTML report section {heading!r}: level = {level!r}, valid "
                              "2, 3, 4")
        self.heading = heading
        self.level = level
        self.blocks = []

    def paragraph(self, text, css_class=None):
        """Add a paragraph of escaped text (``css_class``: pass, fail or warn)."""
        attribute = f' class="{html.escape(css_class)}"' if css_class else ""
        self.blocks.append(f"<p{attribute}>{_text(text)}</p>")
        return self

    def bullets(self, items):
        """Add an unordered list; each item is text or a :func:`link`."""
        body = "".join(f"<li>{_text(item)}</li>" for item in items)
        self.blocks.append(f"<ul>{body}</ul>")
        return self

    def preformatted(self, text):
        """Add preformatted text (escaped)."""
        self.blocks.append(f"<pre>{html.escape(str(text))}</pre>")
        return self

    def table(self, columns, rows, caption=None):
        """Add a table.

        Parameters
        ----------
        columns : sequence of Column or str
            Headers; a string is a column without unit.
        rows : iterable of sequences
            One value per column (see the module docstring for how cells print).
        caption : str, optional
        """
        columns = [c if isinstance(c, Column) else Column(str(c)) for c in columns]
        parts = ["<table>"]
        if caption:
            parts.append(f"<caption>{html.escape(caption)}</caption>")
        parts.append("<thead><tr>" + "".join(f"<th>{html.escape(c.header)}</th>"
                                             for c in columns) + "</tr></thead><tbody>")
        for index, row in enumerate(rows):
            row = list(row)
            if len(row) != len(columns):
                raise ConfigError(f"HTML report table {caption or self.heading!r}: row {index} "
                                  f"has {len(row)} cells for {len(columns)} columns")
            parts.append("<tr>" + "".join(_cell(v, c) for v, c in zip(row, columns)) + "</tr>")
        parts.append("</tbody></table>")
        self.blocks.append("".join(parts))
        return self

    def figure(self, source, caption, alt=None, dpi=110):
        """Add a figure embedded as a PNG data URI (see :func:`png_data_uri`)."""
        uri = png_data_uri(source, dpi=dpi)
        alt_text = html.escape(alt or caption, quote=True)
        self.blocks.append(f'<figure><img src="{uri}" alt="{alt_text}">'
                           f"<figcaption>{html.escape(caption)}</figcaption></figure>")
        return self

    def render(self):
        """The section's markup."""
        tag = f"h{self.level}"
        return f"<section><{tag}>{html.escape(self.heading)}</{tag}>" + "".join(
            self.blocks) + "</section>"


class HtmlReport:
    """A self-contained HTML page: title, intro and sections (see the module docstring).

    Parameters
    ----------
    title : str
    intro : str, optional
        A lead paragraph under the title.
    """

    def __init__(self, title, intro=None):
        self.title = title
        self.intro = intro
        self.sections = []

    def section(self, heading, level=2):
        """Append and return a new :class:`Section`."""
        section = Section(heading, level)
        self.sections.append(section)
        return section

    def render(self):
        """The whole page as a string."""
        intro = f"<p>{_text(self.intro)}</p>" if self.intro else ""
        body = "".join(section.render() for section in self.sections)
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{html.escape(self.title)}</title><style>{_STYLE}</style></head>"
                f"<body><h1>{html.escape(self.title)}</h1>{intro}{body}</body></html>\n")

    def write(self, path):
        """Write the page (UTF-8) atomically: a reader never sees a half-written file.

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        Path
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, temporary = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as stream:
                stream.write(self.render())
            os.chmod(temporary, 0o666 & ~_umask())  # mkstemp's 0600 would hide it from others
            os.replace(temporary, path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise
        return path

"""How reports are written: one document model, rendered to Markdown and to self-contained HTML.

- :mod:`~orchestrator.report.document`: :class:`Document`, its sections and blocks
  (paragraphs, lists, tables of :class:`Column`, figures) and inline content (code, verdicts,
  links); a study builds one document per report;
- :mod:`~orchestrator.report.markdown`: :func:`render_markdown` / :func:`write_markdown`,
  figures linked relatively;
- :mod:`~orchestrator.report.html`: :func:`render_html` / :func:`write_html`, one file with the
  figures embedded, an explicit escaping policy and no links outside its folder;
  :class:`HtmlReport` for pages with no Markdown twin;
- :mod:`~orchestrator.report.matplotlib_agg`: the Agg backend with a font list that holds
  matplotlib's own fonts.

Imports only :mod:`orchestrator.files` of the orchestrator; build, run, verify and reproduce
use it.
"""

from .document import (Bullets, Code, Column, Document, Figure, Link, Paragraph, Preformatted,
                       Section, Strong, Table, Verdict)
from .html import HtmlReport, embedded_image_sources, link, png_data_uri, render_html, write_html
from .markdown import render_markdown, write_markdown
from .matplotlib_agg import ensure_bundled_fonts, pyplot

__all__ = ["Bullets", "Code", "Column", "Document", "Figure", "HtmlReport", "Link", "Paragraph",
           "Preformatted", "Section", "Strong", "Table", "Verdict", "embedded_image_sources",
           "ensure_bundled_fonts", "link", "png_data_uri", "pyplot", "render_html",
           "render_markdown", "write_html", "write_markdown"]

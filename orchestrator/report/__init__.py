"""What reports are written with: self-contained HTML and matplotlib without a display.

- :mod:`~orchestrator.report.html`: :class:`HtmlReport`, one self-contained file (figures
  embedded, no network links, no absolute paths) with an explicit escaping policy;
- :mod:`~orchestrator.report.matplotlib_agg`: the Agg backend with a font list that holds
  matplotlib's own fonts.

Imports nothing else of the orchestrator; build, run, verify and reproduce use it.
"""

from .html import Column, HtmlReport, Section, embedded_image_sources, link, png_data_uri
from .matplotlib_agg import ensure_bundled_fonts, pyplot

__all__ = ["Column", "HtmlReport", "Section", "embedded_image_sources", "ensure_bundled_fonts",
           "link", "png_data_uri", "pyplot"]

"""Render an HTML report in headless Chromium and count the images that really loaded.

A copy of the page gets a small script that, on the window's ``load`` event, writes
``loaded/total`` (images with ``naturalWidth > 0`` / all ``<img>``) into an element; Chromium's
``--dump-dom`` prints the DOM after the page has loaded and we read the count back. Chromium
runs with no network features (no sync, no component update, QUIC off) and a throw-away
profile. Where Chromium is missing, :func:`chromium_path` returns None and the caller checks
that every image is embedded data instead (and says why it skipped the browser).
"""

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

__all__ = ["chromium_path", "inspect_report", "render_image_count", "ChromiumUnavailable"]

_MARKER_ID = "sonotrack-image-check"
_SCRIPT = (
    "<script>window.addEventListener('load', function () {"
    "var images = Array.from(document.images);"
    "var loaded = images.filter(function (i) { return i.complete && i.naturalWidth > 0; });"
    f"var out = document.createElement('div'); out.id = '{_MARKER_ID}';"
    "out.textContent = loaded.length + '/' + images.length;"
    "document.body.appendChild(out); });</script>"
)


class ChromiumUnavailable(RuntimeError):
    """Chromium is not installed or does not start here; the message says why."""


def chromium_path():
    """The Chromium executable, or None when it is not installed."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


def render_image_count(html_path, timeout=90.0):
    """Load ``html_path`` in headless Chromium; return ``(loaded, total)`` images.

    Parameters
    ----------
    html_path : str or Path
    timeout : float
        Seconds before Chromium is stopped.

    Returns
    -------
    tuple of int

    Raises
    ------
    ChromiumUnavailable
        If no Chromium is installed, or it ran but printed no DOM (the reason is its stderr).
    """
    executable = chromium_path()
    if executable is None:
        raise ChromiumUnavailable("no chromium executable on PATH (Debian package `chromium` "
                                  "not installed: `make chromium` needs apt and root)")
    page = Path(html_path).read_text(encoding="utf-8")
    if "</body>" not in page:
        raise AssertionError(f"{html_path}: no </body> to attach the image check to")
    with tempfile.TemporaryDirectory(prefix="sonotrack-chromium-") as work:
        probe = Path(work) / "page.html"
        probe.write_text(page.replace("</body>", _SCRIPT + "</body>", 1), encoding="utf-8")
        command = [executable, "--headless", "--no-sandbox", "--disable-gpu",
                   "--disable-quic", "--no-first-run", "--disable-background-networking",
                   "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                   f"--user-data-dir={Path(work) / 'profile'}",
                   "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()]
        result = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    match = re.search(rf'id="{_MARKER_ID}">(\d+)/(\d+)<', result.stdout)
    if match is None:
        raise ChromiumUnavailable(f"chromium exited {result.returncode} without the image "
                                  f"count; stderr tail: {result.stderr[-600:]!r}")
    return int(match.group(1)), int(match.group(2))


_REPORT_ID = "sonotrack-report-check"
# What a reader of a report meets, measured in the page as Chromium laid it out.
_REPORT_SCRIPT = (
    "<script>window.addEventListener('load', function () {"
    "var images = Array.from(document.images);"
    "var loaded = images.filter(function (i) { return i.complete && i.naturalWidth > 0; });"
    "var links = Array.from(document.querySelectorAll('a[href^=\"#\"]'));"
    "var broken = links.filter(function (a) {"
    "  return !document.getElementById(decodeURIComponent(a.getAttribute('href').slice(1))); })"
    "  .map(function (a) { return a.getAttribute('href'); });"
    "var verdicts = [], unclassed = [];"
    "Array.from(document.querySelectorAll('table')).forEach(function (t) {"
    "  var heads = Array.from(t.querySelectorAll('thead th')).map(function (h) {"
    "    return h.textContent.trim().toLowerCase(); });"
    "  heads.forEach(function (h, i) { if (h.indexOf('verdict') !== 0) return;"
    "    Array.from(t.querySelectorAll('tbody tr')).forEach(function (r) {"
    "      var c = r.children[i]; verdicts.push(c.textContent);"
    "      var spans = c.querySelectorAll('span.pass, span.fail, span.warn').length;"
    "      if (!/\\b(pass|fail|warn)\\b/.test(c.className) && !spans)"
    "        unclassed.push(c.textContent);"
    "      else if (spans) return;"
    "      else if (getComputedStyle(c).backgroundColor === 'rgba(0, 0, 0, 0)')"
    "        unclassed.push('uncoloured: ' + c.textContent); }); }); });"
    "var summary = document.getElementById('summary');"
    "var out = document.createElement('pre'); out.id = '" + _REPORT_ID + "';"
    "out.textContent = JSON.stringify({images: [loaded.length, images.length],"
    " anchors: links.length, broken_anchors: broken, verdict_cells: verdicts.length,"
    " unclassed_verdicts: unclassed,"
    " summary_top: summary ? summary.getBoundingClientRect().top + window.scrollY : null,"
    " summary_text: summary ? summary.textContent : null,"
    " contents: !!document.getElementById('contents'),"
    " height: document.documentElement.scrollHeight});"
    "document.body.appendChild(out); });</script>"
)


def _chromium(arguments, work, timeout):
    executable = chromium_path()
    if executable is None:
        raise ChromiumUnavailable("no chromium executable on PATH (Debian package `chromium` "
                                  "not installed: `make chromium` needs apt and root)")
    command = [executable, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
               "--no-first-run", "--disable-background-networking", "--disable-component-update",
               "--disable-sync", "--disable-dev-shm-usage", "--hide-scrollbars",
               f"--user-data-dir={Path(work) / 'profile'}", "--window-size=1280,1600",
               "--virtual-time-budget=5000", *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout)


def inspect_report(html_path, screenshot=None, timeout=90.0):
    """Load a report page in headless Chromium, 1280 px wide; return what a reader meets.

    Parameters
    ----------
    html_path : str or Path
    screenshot : str or Path, optional
        Where to save a PNG of the page's first 1600 px.

    Returns
    -------
    dict
        ``images`` (loaded, total), ``anchors`` (in-page links), ``broken_anchors`` (those
        naming no element), ``verdict_cells`` and ``unclassed_verdicts`` (cells of a column
        headed "verdict..." neither classed pass/fail/warn with a background colour nor
        holding verdicts each in its classed span), ``summary_top``
        (px from the top of the page, None without a summary), ``summary_text``, ``contents``
        (a table of contents exists), ``height`` (px).

    Raises
    ------
    ChromiumUnavailable
        If Chromium is missing or printed no result.
    """
    import json

    page = Path(html_path).read_text(encoding="utf-8")
    if "</body>" not in page:
        raise AssertionError(f"{html_path}: no </body> to attach the check to")
    with tempfile.TemporaryDirectory(prefix="sonotrack-chromium-") as work:
        probe = Path(work) / "page.html"
        probe.write_text(page.replace("</body>", _REPORT_SCRIPT + "</body>", 1),
                         encoding="utf-8")
        result = _chromium(["--dump-dom", probe.as_uri()], work, timeout)
        if screenshot is not None:
            original = Path(work) / "original.html"
            original.write_text(page, encoding="utf-8")
            _chromium([f"--screenshot={Path(screenshot).resolve()}", original.as_uri()], work,
                      timeout)
    match = re.search(rf'id="{_REPORT_ID}">(.*?)</pre>', result.stdout, flags=re.S)
    if match is None:
        raise ChromiumUnavailable(f"chromium exited {result.returncode} without the report "
                                  f"check; stderr tail: {result.stderr[-600:]!r}")
    import html as html_module

    return json.loads(html_module.unescape(match.group(1)))

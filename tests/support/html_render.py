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

__all__ = ["chromium_path", "render_image_count", "ChromiumUnavailable"]

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

"""matplotlib for the reports: the Agg backend, with a font list that holds matplotlib's own fonts.

matplotlib keeps one font list per user (``~/.cache/matplotlib/fontlist-v<version>.json``),
shared by every installation of that version. A process whose matplotlib is deleted under it
(a virtual environment removed while one of its processes still draws) rebuilds that list
without the fonts matplotlib ships in ``mpl-data/fonts/ttf`` (STIX, Computer Modern, DejaVu Sans
Display). From then on, every process that typesets mathtext, such as the ``10^k`` tick labels
of a log axis, asks for those families, does not find them and prints ``findfont: Font family
['STIXGeneral'] not found`` on stderr, and the figure falls back to other glyphs.
:func:`ensure_bundled_fonts` adds the shipped fonts the list lacks (``FontManager.addfont``)
and writes the repaired list back, so the next process starts from a whole list.
"""

import contextlib
from pathlib import Path

__all__ = ["ensure_bundled_fonts", "pyplot"]

_CHECKED = False


def ensure_bundled_fonts():
    """Make sure matplotlib's font list holds every font matplotlib ships; once per process.

    Returns
    -------
    list of str
        File names of the fonts that were missing and are now added (empty almost always).
    """
    global _CHECKED
    if _CHECKED:
        return []
    import matplotlib
    from matplotlib import font_manager

    manager = font_manager.fontManager
    known = {Path(font.fname).name for font in manager.ttflist}
    shipped = Path(matplotlib.get_data_path(), "fonts", "ttf")
    missing = sorted(path for path in shipped.glob("*.ttf") if path.name not in known)
    for path in missing:
        manager.addfont(str(path))
    if missing:
        # Repair the shared list too; a cache we may not write is matplotlib's own concern.
        cache = Path(matplotlib.get_cachedir(),
                     f"fontlist-v{font_manager.FontManager.__version__}.json")
        with contextlib.suppress(OSError):
            font_manager.json_dump(manager, cache)
    _CHECKED = True
    return [path.name for path in missing]


def pyplot():
    """matplotlib's pyplot on the Agg backend (no display needed), with a whole font list."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ensure_bundled_fonts()
    return plt

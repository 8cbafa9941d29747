"""A font list that lacks matplotlib's own fonts no longer fills stderr with findfont lines.

The stale list is made the way it happens: matplotlib's per-user font list written without the
fonts shipped in mpl-data (here: by removing them from a fresh list). Each drawing runs in a
child process with its own MPLCONFIGDIR, so the user's real font list is never touched.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[4]

_STALE = """
from pathlib import Path
import matplotlib
from matplotlib import font_manager
shipped = Path(matplotlib.get_data_path(), "fonts")
manager = font_manager.FontManager()
manager.ttflist = [f for f in manager.ttflist if shipped not in Path(f.fname).parents]
font_manager.json_dump(manager, Path(matplotlib.get_cachedir(),
                       f"fontlist-v{font_manager.FontManager.__version__}.json"))
"""
# A log axis: its 10^k tick labels are mathtext, which needs the STIX and Computer Modern fonts.
_DRAW = """
import sys
if sys.argv[1] == "ours":
    from orchestrator.report.matplotlib_agg import pyplot
    plt = pyplot()
else:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
fig, ax = plt.subplots()
ax.semilogy([1, 2, 3], [1e-3, 1e-1, 1e1])
fig.savefig(sys.argv[2])
"""


def _python(code, config, *args):
    env = {**os.environ, "MPLCONFIGDIR": str(config), "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True,
                          text=True, timeout=300, check=True)


@pytest.fixture
def stale_config(tmp_path):
    config = tmp_path / "mplconfig"
    config.mkdir()
    _python(_STALE, config)
    return config


def _families(config):
    (fontlist,) = config.glob("fontlist-v*.json")
    return {font["name"] for font in json.loads(fontlist.read_text())["ttflist"]}


def test_the_stale_list_reproduces_the_warnings(stale_config, tmp_path):
    assert "STIXGeneral" not in _families(stale_config)
    drawn = _python(_DRAW, stale_config, "plain", str(tmp_path / "plain.png"))
    assert "findfont: Font family ['STIXGeneral'] not found" in drawn.stderr


def test_our_figures_repair_the_list_and_print_nothing(stale_config, tmp_path):
    drawn = _python(_DRAW, stale_config, "ours", str(tmp_path / "ours.png"))
    assert "findfont" not in drawn.stderr, drawn.stderr
    assert {"STIXGeneral", "cmr10", "DejaVu Sans Display"} <= _families(stale_config)
    # the repaired list serves a plain matplotlib process too
    again = _python(_DRAW, stale_config, "plain", str(tmp_path / "plain.png"))
    assert "findfont" not in again.stderr, again.stderr

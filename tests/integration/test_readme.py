"""The README's five lines of fmpy, run on freshly built FMUs."""

import re

import pytest

from orchestrator.builder.fmus import REPO_ROOT

pytestmark = pytest.mark.integration


def test_the_fmpy_example_of_the_readme_runs(fmu_dir, monkeypatch):
    text = (REPO_ROOT / "README.md").read_text(encoding="utf-8")
    (example,) = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(example.strip().splitlines()) <= 5
    code = example.replace('"fmus/RobotPlant.fmu"', repr(str(fmu_dir / "RobotPlant.fmu")))
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)   # the README's own code
    result = namespace["result"]
    # driven straight ahead (+y) from rest, both wheels alike: it moved forward, not sideways
    assert result["y"][-1] > 0.1 and abs(result["x"][-1]) < 1e-9

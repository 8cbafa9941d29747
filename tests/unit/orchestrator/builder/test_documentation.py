"""FMU metadata from pyproject.toml (orchestrator.builder.documentation), without building an FMU."""

import pytest

from components.common.errors import BuildError
from orchestrator.builder.documentation import documentation_page, project_metadata

PYPROJECT = """
[project]
name = "sonotrack"
version = "9.8.7"
license = { text = "MIT" }
authors = [{ name = "A. Author" }, { name = "B. Author" }]

[tool.sonotrack]
copyright = "Copyright (c) 2026 A. Author"
"""

MODEL_DESCRIPTION = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Demo" guid="g-1" description="a demo">
  <CoSimulation modelIdentifier="Demo"/>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="0" causality="input" description="in">
      <Real unit="m" start="0.5" min="0" max="2"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="1" causality="output" description="out">
      <Real unit="m"/></ScalarVariable>
    <ScalarVariable name="z" valueReference="2" causality="output" description="out2">
      <Real unit="m"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs>
    <Unknown index="2" dependencies=""/>
    <Unknown index="3" dependencies="1"/>
  </Outputs></ModelStructure>
</fmiModelDescription>
"""


def test_metadata_comes_from_pyproject(tmp_path):
    path = tmp_path / "pyproject.toml"
    path.write_text(PYPROJECT)
    metadata = project_metadata(path)
    assert metadata["version"] == "9.8.7"
    assert metadata["author"] == "A. Author, B. Author"
    assert metadata["license"] == "MIT"
    assert metadata["copyright"] == "Copyright (c) 2026 A. Author"
    assert metadata["generationTool"] == "sonotrack 9.8.7 (pythonfmu 0.7.0)"


def test_missing_metadata_is_a_build_error_naming_the_fields(tmp_path):
    path = tmp_path / "pyproject.toml"
    path.write_text(PYPROJECT.replace('authors = [{ name = "A. Author" }, { name = "B. Author" }]',
                                      "").replace("[tool.sonotrack]", "[tool.other]"))
    with pytest.raises(BuildError, match="project.authors, tool.sonotrack.copyright"):
        project_metadata(path)


def test_page_shows_ranges_and_direct_dependencies_from_the_xml():
    page = documentation_page(MODEL_DESCRIPTION)
    assert "<td>u</td><td>Real</td><td>m</td><td>0.5</td><td>0</td><td>2</td>" in page
    assert "<td>y</td><td>Real</td><td>m</td><td></td><td></td><td></td><td>none</td>" in page
    assert "<td>z</td><td>Real</td><td>m</td><td></td><td></td><td></td><td>u</td>" in page


def test_requirements_are_the_imports_outside_the_stdlib_and_the_fmu_itself():
    from orchestrator.builder.documentation import python_requirements

    files = [("resources/Plant.py", b"import numpy as np\nfrom _own.plant import core\n"),
             ("resources/_own/plant/core.py",
              b"import math, json\ndef f():\n    import scipy.signal\n"
              b"    from . import sibling\n"),
             ("resources/_own/__init__.py", b""), ("modelDescription.xml", b"<x/>"),
             ("resources/notes.txt", b"import pandas")]   # not Python: not read
    assert python_requirements(files) == ["numpy", "scipy"]
    assert python_requirements(files[2:]) == []

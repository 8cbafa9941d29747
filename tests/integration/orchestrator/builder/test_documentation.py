"""Every built FMU carries its metadata and a documentation page that matches its ports."""

import re
import tomllib
import zipfile
from xml.etree import ElementTree

import pytest

from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT
from orchestrator.builder.documentation import DOCUMENTATION_FILE, documentation_problems

pytestmark = pytest.mark.integration

NAMES = list(FMU_PACKAGES)


def _model_description(path):
    with zipfile.ZipFile(path) as archive:
        return ElementTree.fromstring(archive.read("modelDescription.xml"))


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_model_description_carries_the_project_metadata(fmu_paths, name):
    with open(REPO_ROOT / "pyproject.toml", "rb") as stream:
        project = tomllib.load(stream)
    root = _model_description(fmu_paths[name])
    version = project["project"]["version"]
    assert root.get("version") == version
    assert root.get("license") == project["project"]["license"]["text"]
    assert root.get("author") == project["project"]["authors"][0]["name"]
    assert root.get("copyright") == project["tool"]["sonotrack"]["copyright"]
    assert root.get("generationTool") == f"sonotrack {version} (pythonfmu 0.7.0)"
    assert len(root.get("description", "")) > 20


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_documentation_lists_every_port_and_is_self_contained(fmu_paths, name):
    path = fmu_paths[name]
    assert documentation_problems(path) == []
    with zipfile.ZipFile(path) as archive:
        page = archive.read(DOCUMENTATION_FILE).decode("utf-8")
    root = _model_description(path)
    assert root.get("guid") in page and "fmpy.simulate_fmu" in page
    assert "ecos simulate" in page and "fmi2DoStep" in page
    for variable in root.find("ModelVariables"):
        assert variable.get("name") in page
    # the model's docs page rendered, not shown as raw Markdown
    body = page.split('id="what-the-model-computes"', 1)[1]
    prose = re.sub(r"<code>.*?</code>|<pre>.*?</pre>", "", body, flags=re.S)
    assert "<h3" in body and "<p>" in body and "\n## " not in body
    assert "`" not in prose and "](" not in prose and "**" not in prose


@pytest.mark.parametrize("name", sorted(FMU_PACKAGES))
def test_documentation_states_the_packages_the_fmu_code_imports(fmu_paths, name):
    """The reference: every import statement of the FMU's own Python, found by a regex."""
    import re
    import sys

    with zipfile.ZipFile(fmu_paths[name]) as archive:
        page = archive.read(DOCUMENTATION_FILE).decode("utf-8")
        sources = [archive.read(n).decode("utf-8") for n in archive.namelist()
                   if n.startswith("resources/") and n.endswith(".py")]
        own = {n.split("/")[1].removesuffix(".py") for n in archive.namelist()
               if n.startswith("resources/")}
    statement = (r"^\s*(?:import\s+([A-Za-z_]\w*)[\w.]*\s*(?:,|as\b|$)"
                 r"|from\s+([A-Za-z_]\w*)[\w.]*\s+import\b)")
    imported = {a or b for text in sources for a, b in re.findall(statement, text, flags=re.M)}
    outside = sorted(imported - own - set(sys.stdlib_module_names))
    assert outside == ["numpy"]
    needs = page.split('id="how-to-run-it"', 1)[1]   # the models' notes may cite scipy tests
    assert "Needs Python 3.11 with numpy on the machine" in needs and "scipy" not in needs


def _with_page(source, target, edit):
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w") as new:
        for item in old.infolist():
            data = old.read(item)
            if item.filename == DOCUMENTATION_FILE:
                data = edit(data.decode("utf-8")).encode("utf-8")
            new.writestr(item, data)
    return target


@pytest.mark.parametrize("edit, expected", [
    (lambda page: page.replace("<td>v_meas</td>", "<td>v_measured</td>"),
     "input v_meas: no row in the page"),
    (lambda page: page.replace("<td>m/s2</td>", "<td>m/s</td>", 1),
     "error_rate: row shows ['Real', 'm/s', '', '', ''], modelDescription says "
     "['Real', 'm/s2', '', '', '']"),
    (lambda page: page.replace("</body>", '<img src="https://example.org/x.png"></body>'),
     "external reference: img src=https://example.org/x.png"),
    (lambda page: page.replace("</table>", "", 1), "HTML: </section> closes <table>"),
], ids=["missing_port", "wrong_unit", "network_image", "unclosed_table"])
def test_documentation_check_catches_a_broken_page(fmu_paths, tmp_path, edit, expected):
    path = _with_page(fmu_paths["WheelController"], tmp_path / "WheelController.fmu", edit)
    assert expected in documentation_problems(path)

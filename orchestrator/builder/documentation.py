"""FMU metadata and ``documentation/index.html``, added to a built FMU as its last build step.

The metadata (author, version, license, copyright, generationTool) comes from
``pyproject.toml`` of the checkout being built, never from an installed copy, so an FMU states
the version of the code it carries. The documentation page is generated from the FMU's *final*
``modelDescription.xml`` (ports, units, causality, defaults, ``min``/``max`` valid ranges,
default experiment), from the slave class's docstring and from the matching ``docs/<part>.md``
(its Markdown rendered as headings, paragraphs, lists and tables), so it cannot disagree with
what the FMU declares. The Python packages it says a host needs are those the code inside the
FMU imports (:func:`python_requirements`), not a list written by hand. The page is
self-contained: one HTML file, inline style, no script, no network link.
"""

import ast
import sys
import tomllib
import zipfile
from html.parser import HTMLParser
from pathlib import Path
from xml.etree import ElementTree

from components.common.errors import BuildError
from orchestrator.files.atomic import atomic_open
from orchestrator.report.html import Column, HtmlReport
from orchestrator.report.markdown_text import add_markdown

__all__ = ["DOCUMENTATION_FILE", "project_metadata", "add_metadata", "documentation_page",
           "document_fmu", "documentation_problems", "python_requirements"]

DOCUMENTATION_FILE = "documentation/index.html"
_REPO_ROOT = Path(__file__).resolve().parents[2]
_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration")


def project_metadata(pyproject=_REPO_ROOT / "pyproject.toml"):
    """Author, version, license and copyright of the project, from ``pyproject.toml``.

    Returns
    -------
    dict
        ``author``, ``version``, ``license``, ``copyright`` and ``generationTool``
        (``"sonotrack <version> (pythonfmu <version>)"``).
    """
    from pythonfmu import __version__ as pythonfmu_version

    with open(pyproject, "rb") as stream:
        data = tomllib.load(stream)
    project = data["project"]
    authors = ", ".join(a["name"] for a in project.get("authors", []) if "name" in a)
    license_ = project.get("license", {})
    license_text = license_.get("text") if isinstance(license_, dict) else str(license_)
    copyright_text = data.get("tool", {}).get("sonotrack", {}).get("copyright")
    missing = [name for name, value in (("project.authors", authors),
                                        ("project.license", license_text),
                                        ("tool.sonotrack.copyright", copyright_text)) if not value]
    if missing:
        raise BuildError(f"{pyproject}: FMU metadata missing: {', '.join(missing)}")
    return {
        "author": authors,
        "version": project["version"],
        "license": license_text,
        "copyright": copyright_text,
        "generationTool": f"{project['name']} {project['version']} "
                          f"(pythonfmu {pythonfmu_version})",
    }


def add_metadata(root, metadata):
    """Set the metadata attributes on a ``fmiModelDescription`` element (in place).

    Raises
    ------
    BuildError
        If the model has no ``description`` (the slave class must set one).
    """
    if not root.get("description"):
        raise BuildError(f"FMU {root.get('modelName')}: the slave class sets no description")
    for name, value in metadata.items():
        root.set(name, value)
    return root


def _variables(root):
    """One dict per ScalarVariable: its attributes and those of its type element."""
    variables = []
    for node in root.find("ModelVariables"):
        typed = next((child for child in node if child.tag in _TYPES), None)
        entry = dict(node.attrib)
        entry["type"] = typed.tag if typed is not None else "?"
        entry.update({k: v for k, v in (typed.attrib if typed is not None else {}).items()})
        variables.append(entry)
    return variables


def _direct_dependencies(root, variables):
    """Output name -> names of the inputs it depends on directly, from ModelStructure/Outputs.

    An output missing from the list, or listed without ``dependencies``, depends on every input
    (FMI 2.0).
    """
    inputs = [v["name"] for v in variables if v.get("causality") == "input"]
    result = {v["name"]: list(inputs) for v in variables if v.get("causality") == "output"}
    outputs = root.find("ModelStructure/Outputs")
    for unknown in (outputs if outputs is not None else []):
        name = variables[int(unknown.get("index")) - 1]["name"]
        listed = unknown.get("dependencies")
        if listed is not None:
            result[name] = [variables[int(i) - 1]["name"] for i in listed.split()]
    return result


def _slave_docstring(slave_file, model_name):
    tree = ast.parse(Path(slave_file).read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == model_name:
            return ast.get_docstring(node) or ""
    return ""


def python_requirements(files):
    """The packages outside Python's standard library that an FMU's code imports.

    Parameters
    ----------
    files : iterable of (str, bytes)
        The FMU's entries (name, content); its ``resources/**.py`` are read, every ``import``
        at any depth counts, and the FMU's own modules (everything under ``resources/``) do
        not.

    Returns
    -------
    list of str
        Top-level package names, sorted (``["numpy"]`` for every sonotrack FMU).
    """
    sources = {name: data for name, data in files
               if name.startswith("resources/") and name.endswith(".py")}
    own = {Path(name).relative_to("resources").parts[0].removesuffix(".py") for name in sources}
    imported = set()
    for name, data in sources.items():
        for node in ast.walk(ast.parse(data, name)):
            if isinstance(node, ast.Import):
                imported |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split(".")[0])
    return sorted(imported - own - set(sys.stdlib_module_names))


def _range(variable, bound):
    return variable.get(bound, "")


def documentation_page(model_description, slave_file=None, notes_file=None,
                       requirements=("numpy",)):
    """Return ``documentation/index.html`` for an FMU, as a string.

    Parameters
    ----------
    model_description : bytes or str
        The FMU's final ``modelDescription.xml``.
    slave_file : path-like, optional
        The slave module; its class docstring says what the model computes.
    notes_file : path-like, optional
        ``docs/<part>.md``, its Markdown rendered into the page.
    requirements : sequence of str
        The packages the FMU's code imports (:func:`python_requirements`).
    """
    root = ElementTree.fromstring(model_description)
    model = root.get("modelName")
    identifier = root.find("CoSimulation").get("modelIdentifier")
    variables = _variables(root)
    report = HtmlReport(f"{model} (FMI 2.0 Co-Simulation)", intro=root.get("description"))

    about = report.section("About this FMU")
    about.table(["field", "value"], [
        ["model name", model], ["version", root.get("version", "")],
        ["author", root.get("author", "")], ["license", root.get("license", "")],
        ["copyright", root.get("copyright", "")],
        ["generation tool", root.get("generationTool", "")],
        ["generated", root.get("generationDateAndTime",
                               "not recorded (a reproducible build: the GUID names its code)")],
        ["GUID", root.get("guid")],
    ])
    experiment = root.find("DefaultExperiment")
    if experiment is not None:
        about.paragraph("Default experiment: " + ", ".join(
            f"{k} = {v} s" for k, v in experiment.attrib.items()))

    port_columns = ["name", "type", Column("unit"), "start", "min", "max", "description"]
    _port_section(report, "Inputs", "Inputs are held between steps; [min, max] is the valid "
                  "range where the FMU declares one. A non-finite value is refused: the step "
                  "returns fmi2Error or fmi2Discard and the log names the port and the value.",
                  port_columns, _port_rows(variables, "input"))
    direct = _direct_dependencies(root, variables)
    _port_section(report, "Outputs", "'direct inputs' are the inputs an output depends on "
                  "without a step (ModelStructure/Outputs); 'none' means the output changes "
                  "only in fmi2DoStep.",
                  port_columns[:-1] + ["direct inputs", "description"],
                  _port_rows(variables, "output",
                             lambda v: ", ".join(direct[v["name"]]) or "none"))
    _port_section(report, "Parameters", "Fixed parameters: set them after fmi2Instantiate and "
                  "before fmi2ExitInitializationMode. 'start' is the default; [min, max] the "
                  "valid range where the FMU declares one.",
                  port_columns, _port_rows(variables, "parameter"))

    computes = report.section("What the model computes")
    docstring = _slave_docstring(slave_file, model) if slave_file is not None else ""
    if docstring:   # numpydoc text: its ``code`` read as Markdown's `code`
        add_markdown(report, docstring.replace("``", "`"), level=2, section=computes)
    if notes_file is not None and Path(notes_file).is_file():
        computes.paragraph(f"From the project documentation ({Path(notes_file).name}):")
        add_markdown(report, Path(notes_file).read_text(encoding="utf-8"), level=2,
                     section=computes)

    stop = experiment.get("stopTime", "10.0") if experiment is not None else "10.0"
    step = experiment.get("stepSize", "0.01") if experiment is not None else "0.01"
    steps = max(10, int(round(float(stop) / float(step))))
    run = report.section("How to run it")
    packages = (f"with {', '.join(requirements)}" if requirements else
                "(its standard library only)")
    run.paragraph(f"Needs Python 3.11 {packages} on the machine (the packages the model's code "
                  "imports): the model's own code is inside the FMU (resources/), the "
                  "repository is not needed. Linux x86-64 uses sonotrack's FMI binary; win64 "
                  "uses pythonfmu's.")
    run.paragraph("With FMPy:")
    run.preformatted(f"import fmpy\nresult = fmpy.simulate_fmu('{model}.fmu', "
                     f"stop_time={stop}, step_size={step})\nprint(result.dtype.names)")
    run.paragraph("With libcosim (libcosimpy):")
    run.preformatted(
        "from libcosimpy.CosimExecution import CosimExecution\n"
        "from libcosimpy.CosimSlave import CosimLocalSlave\n"
        f"execution = CosimExecution.from_step_size(step_size=int(round({step} * 1e9)))\n"
        f"execution.add_local_slave(CosimLocalSlave(fmu_path='{model}.fmu', "
        f"instance_name='{model.lower()}'))\n"
        f"execution.step({steps})")
    run.paragraph("With ecos (the command line in the ecospy wheel; needs libtbb12):")
    run.preformatted(f"ecos simulate --path {model}.fmu --stopTime {stop} --stepSize {step}")
    run.paragraph(
        "From C (any FMI 2.0 host): dlopen binaries/linux64/" + identifier + ".so and call "
        "fmi2Instantiate(name, fmi2CoSimulation, GUID above, 'file://<unzipped>/resources', "
        "callbacks, fmi2False, fmi2False), fmi2SetupExperiment, fmi2EnterInitializationMode, "
        "fmi2Set* for parameters and inputs, fmi2ExitInitializationMode, then per step "
        "fmi2Set* inputs, fmi2DoStep, fmi2Get* outputs; finally fmi2Terminate and "
        "fmi2FreeInstance. No LD_PRELOAD is needed: a host without Python gets the libpython "
        "and Python recorded at build time (override with SONOTRACK_LIBPYTHON and "
        "SONOTRACK_PYTHON, a Python with numpy).")
    return report.render()


def _port_rows(variables, causality, extra=None):
    """Table rows of the variables of one causality: name, type, unit, start, min, max,
    ``extra(variable)`` if given, description."""
    return [[v["name"], v["type"], v.get("unit", ""), v.get("start", ""), _range(v, "min"),
             _range(v, "max"), *([extra(v)] if extra is not None else []),
             v.get("description", "")]
            for v in variables if v.get("causality") == causality]


def _port_section(report, title, explanation, columns, rows):
    """A section of ports: what they are, then their table (or "No inputs." and the like)."""
    section = report.section(title)
    section.paragraph(explanation)
    if rows:
        section.table(columns, rows)
    else:
        section.paragraph(f"No {title.lower()}.")


def _entry(name):
    """A zip entry readable by everyone (zipfile's default for new entries is 0600)."""
    info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    return info


def document_fmu(fmu_path, slave_file=None, notes_file=None, metadata=None):
    """Add metadata to ``modelDescription.xml`` and write ``documentation/index.html``.

    The FMU is rewritten atomically (a new archive replaces the old one).

    Parameters
    ----------
    fmu_path : path-like
        A built FMU.
    slave_file, notes_file : path-like, optional
        See :func:`documentation_page`.
    metadata : dict, optional
        Defaults to :func:`project_metadata`.

    Returns
    -------
    pathlib.Path
    """
    fmu_path = Path(fmu_path)
    metadata = project_metadata() if metadata is None else metadata
    with zipfile.ZipFile(fmu_path) as archive:
        entries = [(info, archive.read(info)) for info in archive.infolist()
                   if info.filename not in ("modelDescription.xml", DOCUMENTATION_FILE)]
        text = archive.read("modelDescription.xml")
    root = add_metadata(ElementTree.fromstring(text), metadata)
    description = (b'<?xml version="1.0" encoding="UTF-8"?>\n'
                   + ElementTree.tostring(root, encoding="utf-8", xml_declaration=False))
    page = documentation_page(description, slave_file, notes_file,
                              python_requirements((i.filename, d) for i, d in entries))
    with (atomic_open(fmu_path, fsync=False) as stream,
          zipfile.ZipFile(stream, "w", zipfile.ZIP_DEFLATED) as archive):
        archive.writestr(_entry("modelDescription.xml"), description)
        for info, data in entries:
            archive.writestr(info, data)
        archive.writestr(_entry(DOCUMENTATION_FILE), page)
    return fmu_path


class _PageParser(HTMLParser):
    """Collects table rows, external references and unclosed or stray tags of a page."""

    _VOID = {"meta", "br", "img", "hr", "link", "input", "col", "wbr", "source"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.external, self.rows = [], [], [], []
        self._row, self._cell = None, None

    def handle_starttag(self, tag, attrs):
        if tag == "script":
            self.errors.append("<script> element")
        for name, value in attrs:
            if name in ("href", "src") and value and not value.startswith(("data:", "#")):
                self.external.append(f"{tag} {name}={value}")
        if tag in self._VOID:
            return
        self.stack.append(tag)
        if tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in self._VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()
        if tag in ("td", "th") and self._row is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr":
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def documentation_problems(fmu_path):
    """Check an FMU's ``documentation/index.html`` against its ``modelDescription.xml``.

    Returns a list of problems (empty when fine): the page is missing, is not well-nested
    HTML, refers to anything outside itself, or lacks a row for a port or parameter whose
    cells show its causality's table values (type, unit, start, min, max).
    """
    with zipfile.ZipFile(fmu_path) as archive:
        names = set(archive.namelist())
        if DOCUMENTATION_FILE not in names:
            return [f"{fmu_path}: no {DOCUMENTATION_FILE}"]
        page = archive.read(DOCUMENTATION_FILE).decode("utf-8")
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    parser = _PageParser()
    parser.feed(page)
    parser.close()
    problems = [f"HTML: {e}" for e in parser.errors]
    problems += [f"HTML: unclosed <{tag}>" for tag in parser.stack]
    problems += [f"external reference: {e}" for e in parser.external]
    rows = {}
    for row in parser.rows:   # the port tables come first; the model's notes may name a port too
        if row:
            rows.setdefault(row[0], row)
    for variable in _variables(root):
        if variable.get("causality") not in ("input", "output", "parameter"):
            continue
        row = rows.get(variable["name"])
        if row is None:
            problems.append(f"{variable['causality']} {variable['name']}: no row in the page")
            continue
        expected = [variable["type"], variable.get("unit", ""), variable.get("start", ""),
                    variable.get("min", ""), variable.get("max", "")]
        if row[1:6] != expected:
            problems.append(f"{variable['name']}: row shows {row[1:6]}, modelDescription "
                            f"says {expected}")
    return problems

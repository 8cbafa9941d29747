"""Reading and writing SSP 1.0 .ssd files (orchestrator.ssp)."""

import os
from pathlib import Path

import pytest
from lxml import etree

from components.common.errors import ConfigError
from orchestrator.ssp import (SONOTRACK_CONNECTIONS, ComponentDescription, Connection,
                              Connector, ParameterValue, SystemDescription, read_ssd,
                              sonotrack_system, ssd_to_string, write_ssd)

REPO = Path(__file__).resolve().parents[4]
COMMITTED_SSD = REPO / "fmus" / "SystemStructure.ssd"


def ssp_schema():
    """The normative SSP 1.0 SystemStructureDescription schema, as pyssp-standard ships it."""
    import pyssp_standard

    schema_dir = os.path.join(os.path.dirname(pyssp_standard.__file__), "resources")
    return etree.XMLSchema(file=os.path.join(schema_dir, "SystemStructureDescription.xsd"))


def every_feature():
    return SystemDescription(
        name="demo",
        components=[
            ComponentDescription(
                "a", "resources/A.fmu",
                [Connector("x", "output", "Real", "m"), Connector("n", "output", "Integer"),
                 Connector("flag", "input", "Boolean"), Connector("mode", "parameter", "String")],
                {"gain": ParameterValue("Real", 0.1), "count": ParameterValue("Integer", -3),
                 "on": ParameterValue("Boolean", False), "mode": ParameterValue("String", "fgs_pd")},
                step_size_hint=0.005),
            ComponentDescription("b", "B.fmu", [Connector("u", "input", "Real", "m")]),
        ],
        connections=[Connection("a", "x", "b", "u")],
        units={"m": {"m": 1.0}, "deg": {"rad": 1.0, "factor": 0.017453292519943295}},
        start_time=0.0, stop_time=12.5, base_step=0.005, parameter_set_name="demo_set",
    )


def test_round_trip_keeps_every_field(tmp_path):
    written = every_feature()
    path = write_ssd(tmp_path / "demo.ssd", written)
    read = read_ssd(path)
    assert read.path == path
    written.path = path
    assert read == written
    # 0.1 is not representable; it must come back as the same double, not a rounded one.
    assert read.components[0].parameters["gain"].value == 0.1


def test_written_file_is_valid_ssp_1_0(tmp_path):
    path = write_ssd(tmp_path / "demo.ssd", every_feature())
    schema = ssp_schema()
    assert schema.validate(etree.parse(str(path))), schema.error_log


def test_committed_ssd_is_the_output_of_the_table():
    text = COMMITTED_SSD.read_text(encoding="utf-8")
    body = text.split("-->", 1)[1].lstrip("\n")
    assert body == ssd_to_string(sonotrack_system()).split("\n", 1)[1]
    assert ssp_schema().validate(etree.parse(str(COMMITTED_SSD)))


def test_committed_ssd_wires_the_design_connections():
    system = read_ssd(COMMITTED_SSD)
    assert [c.name for c in system.components] == [
        "source", "localizer", "planner", "plant", "controller_left", "controller_right"]
    assert [c.source for c in system.components] == [
        "SoundSource.fmu", "AcousticLocalizer.fmu", "CurvaturePlanner.fmu",
        "RobotPlant.fmu", "WheelController.fmu", "WheelController.fmu"]
    assert [str(c) for c in system.connections] == [f"{a} -> {b}"
                                                    for a, b in SONOTRACK_CONNECTIONS]
    assert len(system.connections) == 20
    # libcosim rejects a connection to an undeclared connector: every end must be declared.
    for connection in system.connections:
        assert system.component(connection.start_element).connector(
            connection.start_connector).kind == "output"
        assert system.component(connection.end_element).connector(
            connection.end_connector).kind == "input"
    assert system.component("source").parameters == {"path": ParameterValue("String", "s_curve")}
    assert system.component("localizer").parameters == {"seed": ParameterValue("Integer", 1)}
    assert system.units["V"] == {"kg": 1.0, "m": 2.0, "s": -3.0, "A": -1.0}
    assert (system.start_time, system.stop_time) == (0.0, 30.0)


def test_source_prefix_for_ssp_archives():
    packed = sonotrack_system().with_source_prefix("resources/")
    assert packed.components[0].source == "resources/SoundSource.fmu"
    assert sonotrack_system().components[0].source == "SoundSource.fmu"


BROKEN = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    version="1.0" name="broken">
  <ssd:System name="broken">
    <ssd:Elements>
      <ssd:Component name="a" source="A.fmu">
        <ssd:Connectors>
          <ssd:Connector name="x" kind="outptu"><ssc:Real unit="m"/></ssd:Connector>
          <ssd:Connector kind="input"><ssc:Real/></ssd:Connector>
        </ssd:Connectors>
        <ssd:ParameterBindings>
          <ssd:ParameterBinding>
            <ssd:ParameterValues>
              <ssv:ParameterSet version="1.0" name="p">
                <ssv:Parameters>
                  <ssv:Parameter name="seed"><ssv:Integer value="1.5"/></ssv:Parameter>
                </ssv:Parameters>
              </ssv:ParameterSet>
            </ssd:ParameterValues>
          </ssd:ParameterBinding>
        </ssd:ParameterBindings>
      </ssd:Component>
      <ssd:Component name="b"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="a" startConnector="x" endConnector="u"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


def test_parse_problems_are_listed_together_with_lines(tmp_path):
    path = tmp_path / "broken.ssd"
    path.write_text(BROKEN, encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        read_ssd(path)
    assert str(caught.value).splitlines() == [
        f"{path}: 5 problems in the system structure description:",
        f"  {path}:10: <ssd:Connector name=\"x\">: kind 'outptu' is not one of input, output, "
        f"parameter, calculatedParameter, inout",
        f"  {path}:11: <ssd:Connector>: attribute 'name' is missing",
        f"  {path}:18: <ssv:Parameter name=\"seed\">: value '1.5' is not a valid ssv:Integer",
        f"  {path}:25: <ssd:Component name=\"b\">: attribute 'source' is missing",
        f"  {path}:28: <ssd:Connection>: attribute(s) endElement missing (system-level "
        f"connectors are not supported)",
    ]


def test_unreadable_files_name_the_file(tmp_path):
    with pytest.raises(ConfigError, match=r"missing\.ssd: cannot read"):
        read_ssd(tmp_path / "missing.ssd")
    bad = tmp_path / "bad.ssd"
    bad.write_text("<ssd:SystemStructureDescription", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"bad\.ssd: not well-formed XML"):
        read_ssd(bad)


def test_parameters_from_an_ssv_file(tmp_path):
    (tmp_path / "values.ssv").write_text(
        '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
        ' version="1.0" name="v"><ssv:Parameters>'
        '<ssv:Parameter name="v_cruise"><ssv:Real value="0.3" unit="m/s"/></ssv:Parameter>'
        '<ssv:Parameter name="on"><ssv:Boolean value="1"/></ssv:Parameter>'
        '</ssv:Parameters></ssv:ParameterSet>', encoding="utf-8")
    text = ssd_to_string(SystemDescription("s", [ComponentDescription("p", "P.fmu")]))
    text = text.replace('source="P.fmu"/>', 'source="P.fmu"><ssd:ParameterBindings>'
                        '<ssd:ParameterBinding source="values.ssv"/></ssd:ParameterBindings>'
                        '</ssd:Component>')
    (tmp_path / "s.ssd").write_text(text, encoding="utf-8")
    assert read_ssd(tmp_path / "s.ssd").components[0].parameters == {
        "v_cruise": ParameterValue("Real", 0.3), "on": ParameterValue("Boolean", True)}


def test_committed_ssd_is_portable():
    """One parameter-set name (ecos applies one named set) and libcosim's base step."""
    root = etree.parse(str(COMMITTED_SSD)).getroot()
    namespaces = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
                  "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
    names = {node.get("name") for node in root.iterfind(".//ssv:ParameterSet", namespaces)}
    assert names == {"default"}
    bound = {c.name for c in read_ssd(COMMITTED_SSD).components if c.parameters}
    assert bound == {"source", "localizer"}   # path (String) and seed (Integer) both in "default"
    fixed = root.findall(".//osp:Algorithm/osp:FixedStepAlgorithm", namespaces)
    assert [float(node.get("baseStepSize")) for node in fixed] == [0.01]
    system = read_ssd(COMMITTED_SSD)
    assert system.base_step == 0.01 and system.parameter_set_name == "default"
    # every component's step is a whole multiple of the base step (libcosim's decimation)
    for component in system.components:
        ratio = component.step_size_hint / system.base_step
        assert abs(ratio - round(ratio)) < 1e-9, component.name


@pytest.mark.parametrize("breakage", [
    ('<ssd:DefaultExperiment startTime="0.0"', '<ssd:DefaultExperiment startTime="zero"'),
    ('ssd:Units>', 'ssd:UnitList>'),
    ('kind="output"', 'kind="out"'),
], ids=["non_numeric_start_time", "misspelt_units", "unknown_connector_kind"])
def test_schema_rejects_a_broken_ssd(tmp_path, breakage):
    """The XSD check is not vacuous: small breakages of the committed file fail it."""
    text = COMMITTED_SSD.read_text(encoding="utf-8")
    assert breakage[0] in text
    broken = tmp_path / "broken.ssd"
    broken.write_text(text.replace(*breakage), encoding="utf-8")
    assert not ssp_schema().validate(etree.parse(str(broken)))

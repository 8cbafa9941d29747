"""Checks of orchestrator.system against small synthetic FMUs (modelDescription.xml only).

fmpy's ``read_model_description`` needs only the XML, so each test zips a handwritten model
description into a ``.fmu`` and writes an ``.ssd`` beside it; every planted mistake must come
back as exactly the expected problem line.
"""

import zipfile

import pytest

from components.common.errors import ConfigError
from orchestrator.ssp import (FMU_PORTS, SONOTRACK_INSTANCES, ComponentDescription,
                              Connection, Connector, ParameterValue, SystemDescription,
                              sonotrack_system, write_ssd)
from orchestrator.system import (SystemDescriptionError, algebraic_loops, check_system,
                                 direct_dependencies, gauss_seidel_order, load_system)

ALL = object()   # marker: the output has no dependencies attribute (depends on every input)

_VARIABILITY = {"Real": "continuous", "Integer": "discrete", "Boolean": "discrete",
                "String": "discrete"}
_START = {"Real": "0.0", "Integer": "0", "Boolean": "false", "String": ""}


def fmu_xml(model, ports, depends=None):
    """modelDescription.xml text for ``ports`` = [(name, causality, type, unit)].

    ``depends`` maps output names to the inputs they feed through from (``ALL`` for no
    attribute); outputs not in it depend on nothing.
    """
    depends = depends or {}
    units = sorted({unit for _, _, _, unit in ports if unit})
    lines = [f'<?xml version="1.0" encoding="UTF-8"?>',
             f'<fmiModelDescription fmiVersion="2.0" modelName="{model}" '
             f'guid="{{00000000-0000-0000-0000-000000000000}}" variableNamingConvention="flat" '
             f'numberOfEventIndicators="0">',
             f'  <CoSimulation modelIdentifier="{model}"/>']
    if units:
        lines.append("  <UnitDefinitions>")
        lines += [f'    <Unit name="{u}"><BaseUnit m="1"/></Unit>' for u in units]
        lines.append("  </UnitDefinitions>")
    lines.append("  <ModelVariables>")
    index = {}
    for i, (name, causality, kind, unit) in enumerate(ports, start=1):
        index[name] = i
        variability = "fixed" if causality == "parameter" else _VARIABILITY[kind]
        attributes = f'name="{name}" valueReference="{100 + i}" causality="{causality}" ' \
                     f'variability="{variability}"'
        unit_attribute = f' unit="{unit}"' if unit else ""
        if causality == "output":
            lines.append(f'    <ScalarVariable {attributes} initial="calculated">'
                         f'<{kind}{unit_attribute}/></ScalarVariable>')
        else:
            initial = ' initial="exact"' if causality == "parameter" else ""
            lines.append(f'    <ScalarVariable {attributes}{initial}>'
                         f'<{kind}{unit_attribute} start="{_START[kind]}"/></ScalarVariable>')
    lines.append("  </ModelVariables>")
    lines.append("  <ModelStructure>")
    outputs = [name for name, causality, _, _ in ports if causality == "output"]
    if outputs:
        lines.append("    <Outputs>")
        for name in outputs:
            inputs = depends.get(name, [])
            if inputs is ALL:
                lines.append(f'      <Unknown index="{index[name]}"/>')
            else:
                listed = " ".join(str(index[i]) for i in inputs)
                kinds = " ".join("dependent" for _ in inputs)
                lines.append(f'      <Unknown index="{index[name]}" dependencies="{listed}" '
                             f'dependenciesKind="{kinds}"/>')
        lines.append("    </Outputs>")
        lines.append("    <InitialUnknowns>")
        lines += [f'      <Unknown index="{index[name]}"/>' for name in outputs]
        lines.append("    </InitialUnknowns>")
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines)


def make_fmu(path, model, ports, depends=None):
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("modelDescription.xml", fmu_xml(model, ports, depends))
    return path


# A three-FMU loop in miniature: a sensor samples the plant, a controller with direct feedthrough
# from its reference, a plant without feedthrough (its speed is a state).
SENSOR = [("speed_in", "input", "Real", "m/s"), ("reference", "output", "Real", "m/s"),
          ("gain", "parameter", "Real", "1")]
CONTROLLER = [("v_ref", "input", "Real", "m/s"), ("v_meas", "input", "Real", "m/s"),
              ("voltage", "output", "Real", "V"), ("mode", "parameter", "String", None),
              ("seed", "parameter", "Integer", None)]
PLANT = [("voltage", "input", "Real", "V"), ("speed", "output", "Real", "m/s"),
         ("count", "output", "Integer", None)]


def connectors(ports, names=None):
    return [Connector(name, causality, kind, unit) for name, causality, kind, unit in ports
            if names is None or name in names]


def good_description():
    return SystemDescription(
        name="mini",
        components=[
            ComponentDescription("plant", "Plant.fmu", connectors(PLANT)),
            ComponentDescription("controller", "Controller.fmu", connectors(CONTROLLER),
                                 {"mode": ParameterValue("String", "pd"),
                                  "seed": ParameterValue("Integer", 3)}),
            ComponentDescription("sensor", "Sensor.fmu", connectors(SENSOR)),
        ],
        connections=[
            Connection("sensor", "reference", "controller", "v_ref"),
            Connection("plant", "speed", "controller", "v_meas"),
            Connection("controller", "voltage", "plant", "voltage"),
            Connection("plant", "speed", "sensor", "speed_in"),
        ],
    )


@pytest.fixture
def mini(tmp_path):
    """Write the three FMUs; return (tmp_path, model descriptions by instance)."""
    from fmpy import read_model_description

    make_fmu(tmp_path / "Plant.fmu", "Plant", PLANT)
    make_fmu(tmp_path / "Controller.fmu", "Controller", CONTROLLER,
             {"voltage": ["v_ref", "v_meas"]})
    make_fmu(tmp_path / "Sensor.fmu", "Sensor", SENSOR)
    mds = {"plant": read_model_description(str(tmp_path / "Plant.fmu")),
           "controller": read_model_description(str(tmp_path / "Controller.fmu")),
           "sensor": read_model_description(str(tmp_path / "Sensor.fmu"))}
    return tmp_path, mds


def test_sound_system_loads_with_resolved_connections(mini):
    tmp_path, _ = mini
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", good_description())
    system = load_system(ssd)
    assert [c.name for c in system.components] == ["plant", "controller", "sensor"]
    assert system.components[0].fmu_path == (tmp_path / "Plant.fmu").resolve()
    # Value references come from the XML: 100 + position of the variable.
    wired = [(str(c), c.start.value_reference, c.end.value_reference, c.start.type, c.end.unit)
             for c in system.connections]
    assert wired == [
        ("sensor.reference -> controller.v_ref", 102, 101, "Real", "m/s"),
        ("plant.speed -> controller.v_meas", 102, 102, "Real", "m/s"),
        ("controller.voltage -> plant.voltage", 103, 101, "Real", "V"),
        ("plant.speed -> sensor.speed_in", 102, 101, "Real", "m/s"),
    ]
    assert system.parameter_values == {"controller.mode": ParameterValue("String", "pd"),
                                       "controller.seed": ParameterValue("Integer", 3)}
    assert system.variable("plant.count").type == "Integer"


def test_stepping_order_respects_feedthrough_and_breaks_ties_by_ssd_order(mini):
    tmp_path, mds = mini
    # controller.voltage depends on v_ref and v_meas, so sensor and plant must step first; the
    # edges into plant and sensor carry no feedthrough, so the two keep their .ssd order.
    assert gauss_seidel_order(good_description(), mds) == ["plant", "sensor", "controller"]
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", good_description())
    assert load_system(ssd).stepping_order() == ["plant", "sensor", "controller"]


def test_stepping_order_without_feedthrough_is_ssd_order(mini):
    tmp_path, mds = mini
    from fmpy import read_model_description

    make_fmu(tmp_path / "Lazy.fmu", "Controller", CONTROLLER)   # voltage depends on nothing
    mds["controller"] = read_model_description(str(tmp_path / "Lazy.fmu"))
    assert gauss_seidel_order(good_description(), mds) == ["plant", "controller", "sensor"]


@pytest.mark.parametrize("first", ["a", "b"], ids=["a-first", "b-first"])
def test_component_cycle_without_variable_loop_falls_back_to_ssd_order(tmp_path, first):
    from fmpy import read_model_description

    # a.o1 -> b.i1 (feeds b.o1) and b.o1 -> a.i2 (feeds a.o2): each component must step before
    # the other, yet no variable loop exists. The earlier one in the .ssd steps first.
    ports = [("i1", "input", "Real", "m"), ("i2", "input", "Real", "m"),
             ("o1", "output", "Real", "m"), ("o2", "output", "Real", "m")]
    make_fmu(tmp_path / "Two.fmu", "Two", ports, {"o1": ["i1"], "o2": ["i2"]})
    md = read_model_description(str(tmp_path / "Two.fmu"))
    names = ["a", "b"] if first == "a" else ["b", "a"]
    description = SystemDescription("cycle", [ComponentDescription(n, "Two.fmu", connectors(ports))
                                              for n in names],
                                    [Connection("a", "o1", "b", "i1"),
                                     Connection("b", "o1", "a", "i2")])
    mds = {"a": md, "b": md}
    assert algebraic_loops(description, mds) == []
    assert gauss_seidel_order(description, mds) == names
    assert check_system(description, mds, allow_unconnected={"a.i1", "b.i2"}) == []


def test_missing_fmu_is_an_unknown_component(mini):
    tmp_path, _ = mini
    (tmp_path / "Sensor.fmu").unlink()
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", good_description())
    with pytest.raises(SystemDescriptionError) as caught:
        load_system(ssd)
    problems = caught.value.problems
    assert problems[0] == (f"component 'sensor': unknown component, FMU 'Sensor.fmu' not found "
                           f"at {(tmp_path / 'Sensor.fmu').resolve()}")
    # Without the sensor, controller.v_ref has no valid driver left to check, but nothing else.
    assert len(problems) == 1


def test_unknown_port_in_connector_and_connection(mini):
    _, mds = mini
    description = good_description()
    description.components[1].connectors[0] = Connector("v_rf", "input", "Real", "m/s")
    description.connections[0] = Connection("sensor", "reference", "controller", "v_rf")
    assert check_system(description, mds) == [
        "controller.v_rf: unknown port, Controller has no variable 'v_rf' (did you mean "
        "'v_ref'?); its inputs are: v_ref, v_meas",
        "controller.v_ref: input is not connected (connect it or list it in allow_unconnected)",
    ]


def test_connection_to_undeclared_connector_and_unknown_component(mini):
    _, mds = mini
    description = good_description()
    description.components[0].connectors = connectors(PLANT, {"voltage", "count"})
    description.connections.append(Connection("sensr", "reference", "plant", "voltage"))
    assert check_system(description, mds) == [
        "connection plant.speed -> controller.v_meas: plant.speed is not declared in the "
        "<ssd:Connectors> of 'plant' (libcosim needs every connected port declared)",
        "connection plant.speed -> sensor.speed_in: plant.speed is not declared in the "
        "<ssd:Connectors> of 'plant' (libcosim needs every connected port declared)",
        "connection sensr.reference -> plant.voltage: unknown component 'sensr' (did you mean "
        "'sensor'?); components are: plant, controller, sensor",
        # The stray connection still is a second connection into plant.voltage.
        "plant.voltage: input driven by 2 connections: controller.voltage -> plant.voltage, "
        "sensr.reference -> plant.voltage",
    ]


def test_connector_type_and_unit_differ_from_fmu(mini):
    _, mds = mini
    description = good_description()
    description.components[0].connectors[2] = Connector("count", "output", "Real", None)
    description.components[2].connectors[0] = Connector("speed_in", "input", "Real", "rad/s")
    assert check_system(description, mds) == [
        "plant.count: connector type Real but the FMU variable is Integer",
        "sensor.speed_in: connector unit 'rad/s' but the FMU variable has unit 'm/s'",
    ]


def test_connector_kind_differs_from_causality(mini):
    _, mds = mini
    description = good_description()
    description.components[2].connectors[1] = Connector("reference", "input", "Real", "m/s")
    assert check_system(description, mds) == [
        "sensor.reference: connector kind 'input' but the FMU variable's causality is 'output'",
    ]


def test_connection_type_and_unit_mismatch(mini):
    _, mds = mini
    description = good_description()
    # plant.count (Integer) drives controller.v_meas (Real); controller.voltage (V) drives
    # sensor.speed_in (m/s) instead of plant.speed.
    description.connections[1] = Connection("plant", "count", "controller", "v_meas")
    description.connections[3] = Connection("controller", "voltage", "sensor", "speed_in")
    assert check_system(description, mds) == [
        "connection plant.count -> controller.v_meas: type mismatch, plant.count is Integer "
        "and controller.v_meas is Real",
        "connection controller.voltage -> sensor.speed_in: unit mismatch, controller.voltage "
        "has unit 'V' and sensor.speed_in has unit 'm/s'",
    ]


def test_output_to_output_and_input_to_input(mini):
    _, mds = mini
    description = good_description()
    description.connections.append(Connection("plant", "speed", "sensor", "reference"))
    description.connections.append(Connection("controller", "v_meas", "sensor", "speed_in"))
    assert check_system(description, mds) == [
        "connection plant.speed -> sensor.reference: end sensor.reference is an output, not an "
        "input; a connection runs from an output to an input",
        "connection controller.v_meas -> sensor.speed_in: start controller.v_meas is an input, "
        "not an output; a connection runs from an output to an input",
        "sensor.speed_in: input driven by 2 connections: plant.speed -> sensor.speed_in, "
        "controller.v_meas -> sensor.speed_in",
    ]


def test_input_driven_twice(mini):
    _, mds = mini
    description = good_description()
    description.connections.append(Connection("sensor", "reference", "controller", "v_meas"))
    assert check_system(description, mds) == [
        "controller.v_meas: input driven by 2 connections: plant.speed -> controller.v_meas, "
        "sensor.reference -> controller.v_meas",
    ]


def test_unconnected_input_unless_allowed(mini):
    _, mds = mini
    description = good_description()
    del description.connections[3]
    assert check_system(description, mds) == [
        "sensor.speed_in: input is not connected (connect it or list it in allow_unconnected)",
    ]
    assert check_system(description, mds, allow_unconnected={"sensor.speed_in"}) == []
    assert check_system(description, mds, allow_unconnected={"sensor.speed_in",
                                                             "sensor.speed"}) == [
        "allow_unconnected: 'sensor.speed' is not an input of the system (did you mean "
        "'sensor.speed_in'?)",
    ]


def test_parameter_bindings(mini):
    _, mds = mini
    description = good_description()
    description.components[1].parameters = {
        "mode": ParameterValue("Real", 1.0),          # String variable
        "seeed": ParameterValue("Integer", 2),        # typo
        "voltage": ParameterValue("Real", 3.0),       # an output
    }
    assert check_system(description, mds) == [
        "controller.mode: parameter value is ssv:Real 1.0 but the FMU variable is String",
        "controller.seeed: parameter binding names no variable of Controller (did you mean "
        "'seed'?); its parameters are: mode, seed",
        "controller.voltage: bound as a parameter but its causality is 'output'; only "
        "parameter or input variables can be set",
    ]


def test_algebraic_loop_is_printed_as_a_cycle(tmp_path):
    from fmpy import read_model_description

    # The plant now feeds its voltage straight through to speed: controller -> plant ->
    # controller closes a loop, and so does plant -> sensor -> controller -> plant.
    make_fmu(tmp_path / "Plant.fmu", "Plant", PLANT, {"speed": ["voltage"]})
    make_fmu(tmp_path / "Controller.fmu", "Controller", CONTROLLER,
             {"voltage": ["v_ref", "v_meas"]})
    make_fmu(tmp_path / "Sensor.fmu", "Sensor", SENSOR, {"reference": ["speed_in"]})
    mds = {name: read_model_description(str(tmp_path / f"{model}.fmu"))
           for name, model in (("plant", "Plant"), ("controller", "Controller"),
                               ("sensor", "Sensor"))}
    assert check_system(good_description(), mds) == [
        "algebraic loop: plant.speed -> controller.v_meas -> controller.voltage -> "
        "plant.voltage -> plant.speed",
        "algebraic loop: plant.speed -> sensor.speed_in -> sensor.reference -> "
        "controller.v_ref -> controller.voltage -> plant.voltage -> plant.speed",
    ]


def test_missing_dependencies_attribute_means_all_inputs(tmp_path):
    from fmpy import read_model_description

    make_fmu(tmp_path / "Plant.fmu", "Plant", PLANT, {"speed": ALL, "count": []})
    md = read_model_description(str(tmp_path / "Plant.fmu"))
    assert direct_dependencies(md) == {"speed": {"voltage"}, "count": set()}


def test_several_mistakes_are_reported_together(mini):
    tmp_path, _ = mini
    description = good_description()
    description.components[1].connectors[1] = Connector("v_meas", "input", "Integer", None)
    description.components[1].parameters["sed"] = ParameterValue("Integer", 1)
    description.connections[2] = Connection("controller", "voltage", "plant", "voltag")
    del description.connections[3]
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", description)
    with pytest.raises(SystemDescriptionError) as caught:
        load_system(ssd)
    expected = [
        "controller.v_meas: connector type Integer but the FMU variable is Real",
        "controller.sed: parameter binding names no variable of Controller (did you mean "
        "'seed'?); its parameters are: mode, seed",
        "connection controller.voltage -> plant.voltag: plant.voltag is not declared in the "
        "<ssd:Connectors> of 'plant' (libcosim needs every connected port declared)",
        "connection controller.voltage -> plant.voltag: unknown port plant.voltag (did you "
        "mean 'voltage'?); ports of Plant are: voltage, speed, count",
        "plant.voltage: input is not connected (connect it or list it in allow_unconnected)",
        "sensor.speed_in: input is not connected (connect it or list it in allow_unconnected)",
    ]
    assert caught.value.problems == expected
    assert isinstance(caught.value, ConfigError)
    message = str(caught.value)
    assert message.splitlines()[0] == f"{ssd}: 6 problems in the system:"
    assert message.splitlines()[1:] == [f"  {i}. {p}" for i, p in enumerate(expected, 1)]


def test_sonotrack_table_checks_clean_against_matching_fmus(tmp_path):
    """The generated .ssd fits FMUs that have exactly the contract's ports (orchestrator/ssp/sonotrack.py)."""
    for model, ports in FMU_PORTS.items():
        make_fmu(tmp_path / f"{model}.fmu", model, ports)
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", sonotrack_system())
    system = load_system(ssd)
    assert len(system.connections) == 20
    assert system.stepping_order() == list(SONOTRACK_INSTANCES)


def test_sonotrack_plant_with_feedthrough_makes_a_loop(tmp_path):
    for model, ports in FMU_PORTS.items():
        depends = {}
        if model == "WheelController":
            depends = {"voltage": ["v_ref", "v_meas"]}
        if model == "RobotPlant":
            depends = {"wheel_speed_left": ALL}      # a plant that forgot to declare none
        make_fmu(tmp_path / f"{model}.fmu", model, ports, depends)
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", sonotrack_system())
    with pytest.raises(SystemDescriptionError) as caught:
        load_system(ssd)
    assert caught.value.problems == [
        "algebraic loop: plant.wheel_speed_left -> controller_left.v_meas -> "
        "controller_left.voltage -> plant.voltage_left -> plant.wheel_speed_left",
    ]


def test_loop_listing_is_capped_with_a_note(tmp_path):
    # pythonfmu's default ModelStructure (no dependencies attribute) makes every output depend on
    # every input: the sonotrack system then has far more than 20 elementary loops.
    for model, ports in FMU_PORTS.items():
        outputs = {name: ALL for name, kind, _, _ in ports if kind == "output"}
        make_fmu(tmp_path / f"{model}.fmu", model, ports, outputs)
    ssd = write_ssd(tmp_path / "SystemStructure.ssd", sonotrack_system())
    with pytest.raises(SystemDescriptionError) as caught:
        load_system(ssd)
    problems = caught.value.problems
    assert len(problems) == 21
    assert all(p.startswith("algebraic loop: ") for p in problems[:20])
    assert problems[20] == ("more than 20 algebraic loops; only the first 20 are listed "
                            "(declare outputs' direct dependencies in ModelStructure)")

"""The sonotrack system as data: its FMU ports, instances, connections, parameters and steps.

The port table is the contract between the FMUs (docs/system.md); :func:`sonotrack_system` turns it into a
:class:`~orchestrator.ssp.SystemDescription`, and ``python -m orchestrator.ssp [path]``
(:func:`main`) regenerates the committed ``fmus/SystemStructure.ssd`` from it when ports change.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from .model import ComponentDescription, Connection, Connector, ParameterValue, SystemDescription
from .writer import write_ssd

__all__ = [
    "FMU_PORTS",
    "SONOTRACK_INSTANCES",
    "SONOTRACK_CONNECTIONS",
    "SONOTRACK_PARAMETERS",
    "SONOTRACK_STEP_SIZES",
    "sonotrack_system",
    "main",
]

# Ports per FMU model, the contract between the FMUs: (name, kind, type, unit). Only ports whose unit the design
# fixes are listed; extra outputs of an FMU need no connector to be recorded by our master.
FMU_PORTS = {
    "SoundSource": [
        ("x", "output", "Real", "m"),
        ("y", "output", "Real", "m"),
        ("vx", "output", "Real", "m/s"),
        ("vy", "output", "Real", "m/s"),
        ("emitting", "output", "Boolean", None),
        ("path", "parameter", "String", None),
    ],
    "AcousticLocalizer": [
        ("source_x", "input", "Real", "m"),
        ("source_y", "input", "Real", "m"),
        ("emitting", "input", "Boolean", None),
        ("robot_x", "input", "Real", "m"),
        ("robot_y", "input", "Real", "m"),
        ("robot_heading", "input", "Real", "rad"),
        ("distance", "output", "Real", "m"),
        ("bearing", "output", "Real", "rad"),
        ("valid", "output", "Boolean", None),
        ("tdoa_12", "output", "Real", "s"),
        ("tdoa_23", "output", "Real", "s"),
        ("measurement_id", "output", "Integer", None),
        ("seed", "parameter", "Integer", None),
    ],
    "CurvaturePlanner": [
        ("distance", "input", "Real", "m"),
        ("bearing", "input", "Real", "rad"),
        ("valid", "input", "Boolean", None),
        ("measurement_id", "input", "Integer", None),
        ("wheel_speed_left", "input", "Real", "m/s"),
        ("wheel_speed_right", "input", "Real", "m/s"),
        ("v_ref_left", "output", "Real", "m/s"),
        ("v_ref_right", "output", "Real", "m/s"),
        ("radius", "output", "Real", "m"),
        ("curvature", "output", "Real", "1/m"),
        ("arc_remaining", "output", "Real", "m"),
    ],
    "WheelController": [
        ("v_ref", "input", "Real", "m/s"),
        ("v_meas", "input", "Real", "m/s"),
        ("supply_voltage", "input", "Real", "V"),
        ("voltage", "output", "Real", "V"),
    ],
    "RobotPlant": [
        ("voltage_left", "input", "Real", "V"),
        ("voltage_right", "input", "Real", "V"),
        ("x", "output", "Real", "m"),
        ("y", "output", "Real", "m"),
        ("heading", "output", "Real", "rad"),
        ("encoder_left", "output", "Integer", None),
        ("encoder_right", "output", "Integer", None),
        ("wheel_speed_left", "output", "Real", "m/s"),
        ("wheel_speed_right", "output", "Real", "m/s"),
        ("odom_x", "output", "Real", "m"),
        ("odom_y", "output", "Real", "m"),
        ("odom_heading", "output", "Real", "rad"),
        ("supply_voltage_left", "output", "Real", "V"),
        ("supply_voltage_right", "output", "Real", "V"),
    ],
}

# Instance name -> FMU model name, in stepping-tie-break order. No FMU has direct feedthrough,
# so this is the Gauss-Seidel order: the plant steps before the controllers, which then sample
# v_meas at the same instant as the v_ref the planner has just produced (docs/system.md).
SONOTRACK_INSTANCES = {
    "source": "SoundSource",
    "localizer": "AcousticLocalizer",
    "planner": "CurvaturePlanner",
    "plant": "RobotPlant",
    "controller_left": "WheelController",
    "controller_right": "WheelController",
}

SONOTRACK_CONNECTIONS = [
    ("source.x", "localizer.source_x"),
    ("source.y", "localizer.source_y"),
    ("source.emitting", "localizer.emitting"),
    ("plant.x", "localizer.robot_x"),
    ("plant.y", "localizer.robot_y"),
    ("plant.heading", "localizer.robot_heading"),
    ("localizer.distance", "planner.distance"),
    ("localizer.bearing", "planner.bearing"),
    ("localizer.valid", "planner.valid"),
    ("localizer.measurement_id", "planner.measurement_id"),
    ("plant.wheel_speed_left", "planner.wheel_speed_left"),
    ("plant.wheel_speed_right", "planner.wheel_speed_right"),
    ("planner.v_ref_left", "controller_left.v_ref"),
    ("plant.wheel_speed_left", "controller_left.v_meas"),
    ("planner.v_ref_right", "controller_right.v_ref"),
    ("plant.wheel_speed_right", "controller_right.v_meas"),
    ("plant.supply_voltage_left", "controller_left.supply_voltage"),
    ("plant.supply_voltage_right", "controller_right.supply_voltage"),
    ("controller_left.voltage", "plant.voltage_left"),
    ("controller_right.voltage", "plant.voltage_right"),
]

# Only the values that define the default run; everything else keeps the FMU's default and is
# overridden per scenario.
SONOTRACK_PARAMETERS = {
    "source": {"path": ParameterValue("String", "s_curve")},
    "localizer": {"seed": ParameterValue("Integer", 1)},
}

# Communication steps in s (docs/system.md and scenarios/s_curve.toml give the reasoning).
SONOTRACK_STEP_SIZES = {
    "source": 0.01,
    "localizer": 0.01,
    "planner": 0.02,
    "controller_left": 0.02,
    "controller_right": 0.02,
    "plant": 0.02,
}


def _unit_bases():
    # Import lazily: the slave base pulls in pythonfmu, which reading an .ssd does not need.
    from components.common.slave import UNIT_BASES

    bases = {}
    for unit, exponents in UNIT_BASES.items():
        attributes = dict(exponents)
        if unit == "deg":
            attributes["factor"] = math.pi / 180.0
        bases[unit] = attributes
    return bases


def sonotrack_system(stop_time=30.0, fmu_prefix=""):
    """Return the sonotrack system (six FMU instances, 20 connections) as a description.

    Parameters
    ----------
    stop_time : float
        ``stopTime`` of the ``ssd:DefaultExperiment``, in s.
    fmu_prefix : str
        Prefix of every component source: ``""`` for FMUs next to the ``.ssd`` (``fmus/``),
        ``"resources/"`` inside an ``.ssp`` archive.

    Returns
    -------
    SystemDescription
        With ``path=None``; pass it to :func:`write_ssd`.
    """
    components = []
    used_units = set()
    for instance, model in SONOTRACK_INSTANCES.items():
        connectors = [Connector(name, kind, type_name, unit)
                      for name, kind, type_name, unit in FMU_PORTS[model]]
        used_units.update(c.unit for c in connectors if c.unit is not None)
        components.append(ComponentDescription(
            name=instance,
            source=f"{fmu_prefix}{model}.fmu",
            connectors=connectors,
            parameters=dict(SONOTRACK_PARAMETERS.get(instance, {})),
            step_size_hint=SONOTRACK_STEP_SIZES.get(instance),
        ))
    connections = []
    for start, end in SONOTRACK_CONNECTIONS:
        start_element, start_connector = start.split(".")
        end_element, end_connector = end.split(".")
        connections.append(Connection(start_element, start_connector, end_element, end_connector))
    bases = _unit_bases()
    units = {unit: bases[unit] for unit in sorted(used_units)}
    return SystemDescription(name="sonotrack", components=components, connections=connections,
                             units=units, start_time=0.0, stop_time=float(stop_time),
                             base_step=min(SONOTRACK_STEP_SIZES.values()),
                             parameter_set_name="default")


_GENERATED_HEADER = ("Generated by orchestrator/ssp/sonotrack.py (sonotrack_system); regenerate "
                     "with `python -m orchestrator.ssp fmus/SystemStructure.ssd` after port "
                     "changes.")


def main(argv=None):
    """Write the sonotrack ``.ssd`` (default ``fmus/SystemStructure.ssd`` of this checkout)."""
    argv = sys.argv[1:] if argv is None else argv
    default = Path(__file__).resolve().parents[2] / "fmus" / "SystemStructure.ssd"
    target = Path(argv[0]) if argv else default
    write_ssd(target, sonotrack_system(), header=_GENERATED_HEADER)
    print(target)
    return 0

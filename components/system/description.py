"""What the whole-system FMU runs: its instances, connections, schedule and parameter values.

A :class:`SystemDescription` is a run plan of ``sonotrack run`` written down as data
(``orchestrator/run/system_fmu.py`` makes it from a scenario): the instances in stepping
order, each with its model, the sub-package of ``components/`` holding its slave, its rate in
base steps and the parameter values the run sets (``.ssd`` bindings, scenario overrides, fault
schedules, seed); the connections; the base step and master algorithm; the seed; and which
outputs give the robot's and the source's positions. The FMU reads it from
``resources/sonotrack_system.json`` (:data:`DESCRIPTION_FILE`) when it is instantiated.

Examples
--------
>>> text = SystemDescription(
...     name="demo", base_step=0.01, algorithm="gauss-seidel", stop_time=1.0, seed=3,
...     instances=(InstancePlan("source", "SoundSource", "source", 1, {"path": "static"}),),
...     links=()).to_json()
>>> SystemDescription.from_json(text).instances[0].parameters
{'path': 'static'}
"""

import json
import math
from dataclasses import asdict, dataclass, field

from ..common.errors import ConfigError

__all__ = ["DESCRIPTION_FILE", "FORMAT", "InstancePlan", "SystemDescription"]

DESCRIPTION_FILE = "sonotrack_system.json"
FORMAT = 1
_ALGORITHMS = ("gauss-seidel", "jacobi")
_VALUE_TYPES = (str, bool, int, float)


@dataclass(frozen=True)
class InstancePlan:
    """One inner instance of the system.

    Attributes
    ----------
    name : str
        Instance name (``planner``); the FMU's ports of this instance start with it.
    model : str
        Model name, the slave class (``CurvaturePlanner``).
    package : str
        Sub-package of ``components`` whose ``fmu.py`` defines that class (``planner``).
    rate : int
        Base steps per communication step of the instance.
    parameters : dict
        Parameter values set before initialisation (the rest keep the slave's start values).
    seeded : bool
        The instance takes the system's ``seed`` as its ``seed`` parameter.
    """

    name: str
    model: str
    package: str
    rate: int = 1
    parameters: dict = field(default_factory=dict)
    seeded: bool = False


@dataclass(frozen=True)
class SystemDescription:
    """The instances, connections and schedule of a whole-system FMU (see the module docstring).

    Attributes
    ----------
    name : str
        The scenario the description was made from.
    base_step : float
        The master's base step h [s]; a communication step of the FMU is a multiple of it.
    algorithm : {"gauss-seidel", "jacobi"}
        How the master takes inputs within a macro step.
    stop_time : float
        Default experiment stop time [s].
    seed : int
        Start value of the FMU's ``seed`` parameter.
    instances : tuple of InstancePlan
        In stepping order (producers first).
    links : tuple of (str, str)
        ``("instance.output", "instance.input")`` connections.
    robot_position, source_position : tuple of str
        ``("instance.x", "instance.y")`` outputs whose distance is the FMU's
        ``distance_to_source``; empty: the FMU has no such output.
    """

    name: str
    base_step: float
    algorithm: str
    stop_time: float
    seed: int
    instances: tuple
    links: tuple
    robot_position: tuple = ()
    source_position: tuple = ()

    @property
    def macro_rate(self):
        """Base steps after which every instance has stepped (the largest rate)."""
        return max((plan.rate for plan in self.instances), default=1)

    @property
    def packages(self):
        """Sub-packages of ``components`` the instances' slaves live in, each once, in order."""
        return tuple(dict.fromkeys(plan.package for plan in self.instances))

    def to_json(self):
        """The description as JSON text (what the FMU carries)."""
        data = asdict(self)
        data["format"] = FORMAT
        return json.dumps(data, indent=1, allow_nan=False) + "\n"

    @classmethod
    def from_json(cls, text, source=DESCRIPTION_FILE):
        """Read a description written by :meth:`to_json`; every problem at once.

        Raises
        ------
        ConfigError
            Naming ``source`` and each problem.
        """
        try:
            data = json.loads(text)
        except ValueError as error:
            raise ConfigError(f"{source}: not JSON ({error})") from None
        problems = _problems(data)
        if problems:
            raise ConfigError(f"{source}: " + "; ".join(problems))
        instances = tuple(InstancePlan(**plan) for plan in data["instances"])
        return cls(name=data["name"], base_step=float(data["base_step"]),
                   algorithm=data["algorithm"], stop_time=float(data["stop_time"]),
                   seed=data["seed"], instances=instances,
                   links=tuple(tuple(link) for link in data["links"]),
                   robot_position=tuple(data.get("robot_position", ())),
                   source_position=tuple(data.get("source_position", ())))


def _problems(data):
    """Why ``data`` is not a description of format :data:`FORMAT` (empty list: it is)."""
    if not isinstance(data, dict):
        return [f"expected a JSON object, got {type(data).__name__}"]
    problems = []
    if data.get("format") != FORMAT:
        problems.append(f"format {data.get('format')!r} is not {FORMAT}")
    step = data.get("base_step")
    if not (isinstance(step, (int, float)) and math.isfinite(step) and step > 0):
        problems.append(f"base_step {step!r} is not a positive number of seconds")
    if data.get("algorithm") not in _ALGORITHMS:
        problems.append(f"algorithm {data.get('algorithm')!r} is not one of "
                        f"{', '.join(_ALGORITHMS)}")
    if not isinstance(data.get("seed"), int) or isinstance(data.get("seed"), bool):
        problems.append(f"seed {data.get('seed')!r} is not an integer")
    if not isinstance(data.get("name"), str):
        problems.append("name is not a string")
    stop = data.get("stop_time")
    if not (isinstance(stop, (int, float)) and math.isfinite(stop) and stop > 0):
        problems.append(f"stop_time {stop!r} is not a positive number of seconds")
    instances = data.get("instances")
    names = set()
    if not isinstance(instances, list) or not instances:
        problems.append("instances is not a non-empty list")
        instances = []
    for index, plan in enumerate(instances):
        where = f"instances[{index}]"
        if not isinstance(plan, dict) or set(plan) != {"name", "model", "package", "rate",
                                                       "parameters", "seeded"}:
            problems.append(f"{where} does not hold exactly name, model, package, rate, "
                            "parameters, seeded")
            continue
        if not (isinstance(plan["name"], str) and plan["name"].isidentifier()):
            problems.append(f"{where}.name {plan['name']!r} is not an identifier")
        if plan["name"] in names:
            problems.append(f"{where}.name {plan['name']!r} is repeated")
        names.add(plan["name"])
        if not (isinstance(plan["package"], str) and plan["package"].isidentifier()):
            problems.append(f"{where}.package {plan['package']!r} is not an identifier")
        if not isinstance(plan["rate"], int) or isinstance(plan["rate"], bool) or plan["rate"] < 1:
            problems.append(f"{where}.rate {plan['rate']!r} is not a positive integer")
        parameters = plan["parameters"]
        if not isinstance(parameters, dict) or not all(
                isinstance(v, _VALUE_TYPES) for v in parameters.values()):
            problems.append(f"{where}.parameters is not a table of strings, numbers and "
                            "booleans")
    for link in data.get("links", None) or []:
        if not (isinstance(link, list) and len(link) == 2 and all(
                isinstance(end, str) and end.split(".", 1)[0] in names and "." in end
                for end in link)):
            problems.append(f"link {link!r} is not [instance.output, instance.input] of "
                            "known instances")
    if not isinstance(data.get("links"), list):
        problems.append("links is not a list")
    for key in ("robot_position", "source_position"):
        columns = data.get(key, [])
        if columns and not (isinstance(columns, list) and len(columns) == 2 and all(
                isinstance(c, str) and c.split(".", 1)[0] in names for c in columns)):
            problems.append(f"{key} {columns!r} is not [instance.x, instance.y] of known "
                            "instances")
    return problems

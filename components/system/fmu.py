"""The TrackingSystem FMU: the whole closed loop of a scenario in one pythonfmu slave."""

import math
from dataclasses import replace
from pathlib import Path

from pythonfmu import Boolean, Integer, Real, String
from pythonfmu.enums import Fmi2Causality

from ..common.errors import ConfigError, InputError, ParameterError, SimulationError
from ..common.ranges import RangeTable, ValidRange
from ..common.slave import DefaultExperiment, Fmi2Status, SonotrackSlave
from .description import DESCRIPTION_FILE, SystemDescription
from .instances import SlaveHandle, slave_class
from .master import InstanceSpec, Link, Master

__all__ = ["TrackingSystem"]

_CAST = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
_KIND = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}
_PARAMETER = Fmi2Causality.parameter
_DECLARE_OUTPUT = {"Real": "output_real", "Integer": "output_integer",
                   "Boolean": "output_boolean"}
# a step or time within this share of the base step of a whole number of base steps is that
# number (hosts that add up their step sizes drift by far less)
_STEP_TOLERANCE = 1e-6


class TrackingSystem(SonotrackSlave):
    """Every instance of the system, stepped by the master of ``sonotrack run``, in one FMU.

    The FMU runs the slaves of the five sonotrack FMUs (SoundSource, AcousticLocalizer,
    CurvaturePlanner, two WheelControllers, RobotPlant) from its own copy of their code,
    connected as fmus/SystemStructure.ssd connects them, on the multi-rate schedule and with the
    parameter values of the scenario it was built from (.ssd parameter set, scenario overrides,
    seed). A communication step of the FMU is a whole number n of the base step h; it runs the
    master's macro steps k .. k + n - 1 (t_k = t0 + k h, Gauss-Seidel order, inputs held
    between an instance's steps), so its outputs at t equal those `sonotrack run` records at t.

    Ports: every output of every inner instance as <instance>_<output>, every parameter as
    <instance>_<parameter>, one seed for every instance that takes the scenario's seed, and
    distance_to_source (robot to source, true positions). A bad parameter is fmi2Error naming
    the inner component, its parameter and the value; an inner refusal of a step is
    fmi2Discard with the inner component's own log line.
    """

    description = ("The whole sonotrack tracking loop in one FMU: moving sound source, "
                   "acoustic localizer, curvature planner, two wheel controllers and robot "
                   "plant, on the multi-rate schedule of sonotrack run")
    hidden_state = ()   # _get_fmu_state below saves every inner slave in full

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        system = _read_description(self.resources)
        self._system = system
        self._routes = {}
        self._outputs = []   # (FMU output, inner slave, its attribute), copied by _publish
        self._handles = {}
        self._master = None
        self._steps = 0
        self._start_time = 0.0
        self._stop_time = None
        self.default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=system.stop_time,
            step_size=system.base_step * system.macro_rate)
        for plan in system.instances:
            slave = slave_class(plan.model, plan.package)(
                instance_name=plan.name, resources=self.resources, visible=False)
            slave.log_queue = self.log_queue   # one queue: the binary drains this slave's
            _set_parameters(slave, plan)
            self._handles[plan.name] = SlaveHandle(slave)
        self.distance_to_source = math.nan
        self.valid_ranges = self._declare_ports()
        self._publish()

    # ----- ports: parameters routed to the inner slaves, outputs copied from them -----------
    def __getattr__(self, name):
        # only names not found on the object come here: the inner instances' parameters
        routes = self.__dict__.get("_routes")
        if routes is None or name not in routes:
            raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")
        slave, attribute = routes[name][0]
        return getattr(slave, attribute)

    def __setattr__(self, name, value):
        routes = self.__dict__.get("_routes")
        if routes is not None and name in routes:
            for slave, attribute in routes[name]:
                setattr(slave, attribute, value)
        else:
            object.__setattr__(self, name, value)

    def _claim(self, name):
        if not name.isidentifier() or name in self._routes or hasattr(type(self), name) \
                or name in self.__dict__:
            raise ConfigError(f"{DESCRIPTION_FILE}: port {name!r} of the system FMU is not an "
                              "identifier or is already taken")

    def _route(self, name, targets):
        self._claim(name)
        self._routes[name] = targets

    def _publish(self):
        """Copy every inner output into this slave's own attributes (and the distance).

        Hosts read outputs far more often than the FMU steps (every output after every step,
        each a separate attribute read by the FMI binary): plain attributes make each read a
        dictionary look-up instead of a Python call through ``__getattr__``.
        """
        values = self.__dict__
        for name, slave, attribute in self._outputs:
            values[name] = getattr(slave, attribute)
        values["distance_to_source"] = self._distance()

    def _declare_ports(self):
        """Declare distance_to_source, seed, then each instance's outputs and parameters;
        return the range table of the parameters (min/max in the model description)."""
        system = self._system
        entries = {}
        if system.robot_position and system.source_position:
            self.output_real("distance_to_source", "m", "distance from the robot's axle "
                             "midpoint to the source (true positions)")
        seeded = [self._handles[p.name].slave for p in system.instances if p.seeded]
        if seeded:
            self._route("seed", [(slave, "seed") for slave in seeded])
            self.seed = system.seed   # sets each seeded instance's seed
            entry = seeded[0].valid_ranges.parameters["seed"]
            entries["seed"] = replace(entry, name="seed", start=self.seed, description=(
                f"seed of {', '.join(s.instance_name for s in seeded)} (the scenario's seed)"))
            self._declare(_KIND[entry.type], "seed", _PARAMETER, entries["seed"].description)
        for plan in system.instances:
            slave = self._handles[plan.name].slave
            for variable in slave.vars.values():
                if variable.causality.name != "output":
                    continue
                name = f"{plan.name}_{variable.name}"
                self._claim(name)
                self._outputs.append((name, slave, variable.name))
                self.__dict__[name] = getattr(slave, variable.name)
                kind = type(variable).__name__
                text = f"{plan.name}: {variable.description}"
                if kind == "Real":
                    self.output_real(name, slave._units[variable.name], text)
                else:
                    getattr(self, _DECLARE_OUTPUT[kind])(name, text)
            for parameter, entry in slave.valid_ranges.parameters.items():
                if plan.seeded and parameter == "seed":
                    continue
                name = f"{plan.name}_{parameter}"
                self._route(name, [(slave, parameter)])
                entries[name] = replace(entry, name=name, start=getattr(slave, parameter),
                                        description=f"{plan.name}: {entry.description}")
                self._declare(_KIND[entry.type], name, _PARAMETER, entries[name].description,
                              entry.unit)
        step = ValidRange("step_size", "Real", "s", minimum=system.base_step, maximum=math.inf,
                          why="a whole number of base steps")
        return RangeTable(model=type(self).__name__, parameters=entries, inputs={}, step=step,
                          source=DESCRIPTION_FILE)

    # ----- life cycle -------------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time, tolerance):
        self._start_time = float(start_time)
        self._stop_time = stop_time

    def check_parameters(self):
        """Raise :class:`ParameterError` naming every inner parameter outside its valid range.

        Each problem names the inner component, its parameter, the value, the valid range and
        the FMU parameter that sets it.
        """
        problems = []
        for plan in self._system.instances:
            slave = self._handles[plan.name].slave
            for parameter, entry in slave.valid_ranges.parameters.items():
                problem = entry.problem(getattr(slave, parameter))
                if problem is not None:
                    exposed = "seed" if plan.seeded and parameter == "seed" else \
                        f"{plan.name}_{parameter}"
                    problems.append(f"inner component {plan.name}: parameter {problem} "
                                    f"(FMU parameter {exposed})")
        if problems:
            raise ParameterError(f"{self.instance_name}: " + "; ".join(problems))

    def exit_initialization_mode(self):
        self._master = self._initialized_master()
        self._steps = 0
        self._publish()

    def _initialized_master(self):
        """A master over the inner instances, initialised (each inner slave set up and out
        of its initialisation mode, the initial outputs propagated)."""
        system = self._system
        specs = [InstanceSpec(plan.name, self._handles[plan.name], plan.rate, {})
                 for plan in system.instances]
        master = Master(specs, [Link(*link) for link in system.links], system.base_step,
                        system.algorithm)
        master.initialize(start_time=self._start_time, stop_time=self._stop_time)
        return master

    def do_step(self, current_time, step_size):
        system, master = self._system, self._master
        h = system.base_step
        count = step_size / h if math.isfinite(step_size) else math.nan
        steps = round(count) if math.isfinite(count) else 0
        if steps < 1 or abs(count - steps) > _STEP_TOLERANCE:
            return self.refuse("step_size", step_size, f"the communication step must be a "
                               f"whole number of the base step {h!r} s")
        expected = self._start_time + self._steps * h
        if not abs(current_time - expected) <= _STEP_TOLERANCE * h:
            return self.refuse("current_time", current_time, f"the system is at t = "
                               f"{expected!r} s (after {self._steps} base steps)")
        try:
            for k in range(self._steps, self._steps + steps):
                master.step(k)
        except SimulationError as error:
            self._steps = master.steps_done
            self._publish()   # what the instances hold now, for a host that reads them
            if getattr(error.__cause__, "status", None) != 2:
                raise
            self.log(f"{self.instance_name}: {error}", Fmi2Status.error)
            return False
        self._steps += steps
        self._publish()
        return True

    def terminate(self):
        if self._master is not None:
            self._master.terminate()

    def _distance(self):
        system = self._system
        if not (system.robot_position and system.source_position):
            return math.nan
        (rx, ry), (sx, sy) = ([self._output(c) for c in pair] for pair in
                              (system.robot_position, system.source_position))
        return math.hypot(rx - sx, ry - sy)

    def _output(self, column):
        instance, port = column.split(".", 1)
        return float(getattr(self._handles[instance].slave, port))

    # ----- complete FMU state -----------------------------------------------------------------
    def _get_fmu_state(self):
        return {
            "__system__": {"steps": self._steps, "start_time": self._start_time,
                           "stop_time": self._stop_time,
                           "initialized": self._master is not None},
            "__instances__": {name: handle.slave._get_fmu_state()
                              for name, handle in self._handles.items()},
            "__logged_once__": sorted(self._logged_once),
        }

    def _set_fmu_state(self, state):
        problem = self._state_problem(state)
        if problem is not None:
            raise InputError(f"{self.instance_name}: FMU state refused: {problem}")
        saved = state["__system__"]
        if saved["initialized"] and self._master is None:
            self._start_time, self._stop_time = saved["start_time"], saved["stop_time"]
            self._master = self._initialized_master()
        elif not saved["initialized"] and self._master is not None:
            self._master.terminate()
            self._master = None
        for name, handle in self._handles.items():
            handle.slave._set_fmu_state(state["__instances__"][name])
        if self._master is not None:
            self._master.refresh_buffers()
            self._master.steps_done = saved["steps"]
        self._steps = saved["steps"]
        self._start_time, self._stop_time = saved["start_time"], saved["stop_time"]
        self._publish()
        self._logged_once = set(state["__logged_once__"])

    def _state_problem(self, state):
        """Why ``state`` is not a complete state of this system, or None."""
        if not isinstance(state, dict) or set(state) != {"__system__", "__instances__",
                                                         "__logged_once__"}:
            return f"not a state of {type(self).__name__}"
        saved, instances = state["__system__"], state["__instances__"]
        if not isinstance(saved, dict) or set(saved) != {"steps", "start_time", "stop_time",
                                                         "initialized"}:
            return "its system part is not complete"
        if not isinstance(saved["steps"], int) or saved["steps"] < 0:
            return f"steps {saved['steps']!r} is not a step count"
        if not isinstance(instances, dict) or set(instances) != set(self._handles):
            return f"it does not hold exactly the instances {', '.join(self._handles)}"
        for name, handle in self._handles.items():
            problem = handle.slave._state_problem(instances[name])
            if problem is not None:
                return f"instance {name}: {problem}"
        return None


def _read_description(resources):
    """The :class:`SystemDescription` the FMU carries in its resources folder."""
    if resources is None:
        raise ConfigError(f"TrackingSystem: no resources folder to read {DESCRIPTION_FILE} from")
    path = Path(resources) / DESCRIPTION_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ConfigError(f"TrackingSystem: cannot read {path}: {error.strerror}") from None
    return SystemDescription.from_json(text, source=str(path))


def _set_parameters(slave, plan):
    """Give an inner slave the parameter values of its plan, typed as FMI would carry them."""
    declared = {v.name: type(v).__name__ for v in slave.vars.values()
                if v.causality.name == "parameter"}
    unknown = sorted(set(plan.parameters) - set(declared))
    if unknown:
        raise ConfigError(f"{DESCRIPTION_FILE}: instance {plan.name} ({plan.model}) has no "
                          f"parameter {', '.join(unknown)}; valid: {', '.join(declared)}")
    for name, value in plan.parameters.items():
        setattr(slave, name, _CAST[declared[name]](value))

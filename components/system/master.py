"""The co-simulation master: fixed base step, multi-rate, Gauss-Seidel or Jacobi.

It lives in ``components/`` so that one algorithm serves both ``sonotrack run`` (which
imports it as :mod:`orchestrator.run.master`) and the whole-system FMU, which carries it
inside (:mod:`components.system.fmu`; components never import the orchestrator).

Time is ``t_k = t0 + k * h`` from the integer step count ``k``. Instance ``i`` steps when
``k`` is a multiple of its rate ``m_i`` and then advances by ``m_i * h``; between its steps
its inputs are held. In Gauss-Seidel mode instances step in the order given (producers
first), each reading the latest outputs of those already stepped in this macro step; in
Jacobi mode every instance due at ``k`` reads the outputs as they were at ``t_k``.

Value references are resolved once. Each step does at most one batched set and one batched
get per type per instance (through preallocated ctypes arrays) and copies connected values
with a precomputed list of ``(source array, index, destination index)`` per input group. An
input group is set only when a value in it changed since it was last set: FMI inputs keep
their value until set again, so re-sending a held value is a wasted call (most steps, for
inputs fed by a slower instance or by a sample-and-hold output).

Outputs that feed a connection are read after every step of their instance. Outputs someone
else watches (``observed``, e.g. the recorder's columns) ride along in those reads when they
share an instance and type with a connected output (one more value in a get call costs next
to nothing); :meth:`Master.observed_value` then returns them from the buffer without a call.
Other outputs are read on request (:meth:`Master.read_outputs`).
"""

import math
import time as wallclock
from dataclasses import dataclass, field

from ..common.errors import ConfigError, SimulationError

__all__ = ["InstanceSpec", "Link", "Master", "MASTER_ALGORITHMS"]

MASTER_ALGORITHMS = ("gauss-seidel", "jacobi")
_TYPES = ("Real", "Integer", "Boolean")


@dataclass
class InstanceSpec:
    """One FMU instance of a system.

    Attributes
    ----------
    name : str
        Instance name.
    handle : object
        An :class:`orchestrator.fmu.handle.FmuInstance` (or any object with its interface:
        ``variables``, ``instantiate``, ``port_group``, ``read``, ``write``, ``do_step``,
        ``terminate``, ``last_error``).
    rate : int
        Steps of the base step per communication step of this instance.
    parameters : dict
        Parameter values set in initialisation mode.
    """

    name: str
    handle: object
    rate: int = 1
    parameters: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Link:
    """A connection from ``source`` (``instance.port``) to ``destination``."""

    source: str
    destination: str


class _Slot:
    """Ports of one instance, grouped by type, with their buffers."""

    def __init__(self, spec, output_names, input_names):
        self.spec = spec
        handle = spec.handle
        self.outputs = {t: handle.port_group(t, output_names[t]) for t in _TYPES}
        self.inputs = {t: handle.port_group(t, input_names[t]) for t in _TYPES}
        self.output_groups = [g for g in self.outputs.values() if len(g)]
        self.input_groups = [g for g in self.inputs.values() if len(g)]
        # Filled by Master.initialize: (input group, [(source values, i, j), ...]) per group.
        self.feeds = []

    def read_outputs(self):
        handle = self.spec.handle
        for group in self.output_groups:
            handle.read(group)


class Master:
    """Steps a set of connected instances.

    Parameters
    ----------
    instances : list of InstanceSpec
        In stepping order (Gauss-Seidel order; irrelevant for Jacobi).
    links : list of Link
        Connections between outputs and inputs (``"instance.port"`` names).
    base_step : float
        The base step ``h`` in s.
    algorithm : {"gauss-seidel", "jacobi"}
        How inputs are taken within a macro step.
    observed : iterable of str
        Outputs (``"instance.port"``) read often by someone else (the recorder); those of a
        type already read for a connection are read with it (see :meth:`observed_value`).
    """

    def __init__(self, instances, links, base_step, algorithm="gauss-seidel", observed=()):
        if algorithm not in MASTER_ALGORITHMS:
            raise ConfigError(f"master algorithm {algorithm!r} is not one of "
                              f"{', '.join(MASTER_ALGORITHMS)}")
        if not (base_step > 0 and math.isfinite(base_step)):
            raise ConfigError(f"base step {base_step!r} must be a positive number of seconds")
        self.instances = list(instances)
        self.links = list(links)
        self.base_step = float(base_step)
        self.algorithm = algorithm
        self.observed = list(observed)
        self._slots = {}
        self._time = 0.0
        self.steps_done = 0

    # ----- set-up ------------------------------------------------------------------------------
    def initialize(self, start_time=0.0, stop_time=None):
        """Instantiate every instance, resolve ports and propagate the initial outputs."""
        by_name = {spec.name: spec for spec in self.instances}
        outputs = {name: {t: [] for t in _TYPES} for name in by_name}
        inputs = {name: {t: [] for t in _TYPES} for name in by_name}
        for link in self.links:
            instance, port = link.source.split(".", 1)
            variable = by_name[instance].handle.variables[port]
            if port not in outputs[instance][variable.type]:
                outputs[instance][variable.type].append(port)
            instance, port = link.destination.split(".", 1)
            variable = by_name[instance].handle.variables[port]
            inputs[instance][variable.type].append(port)
        for name in self.observed:
            instance, port = name.split(".", 1)
            variable = by_name[instance].handle.variables[port]
            group = outputs[instance][variable.type]
            if group and port not in group:
                group.append(port)
        self.start_time = float(start_time)
        for spec in self.instances:
            try:
                spec.handle.instantiate(start_time=start_time, stop_time=stop_time,
                                        parameters=spec.parameters)
            except Exception as exc:
                said = spec.handle.last_error()
                self.terminate()
                raise SimulationError(f"instance {spec.name} failed to initialise: "
                                      f"{said or exc}") from exc
            self._slots[spec.name] = _Slot(spec, outputs[spec.name], inputs[spec.name])
        feeds = {spec.name: {} for spec in self.instances}
        for link in self.links:
            source_instance, source_port = link.source.split(".", 1)
            target_instance, target_port = link.destination.split(".", 1)
            type_name = by_name[source_instance].handle.variables[source_port].type
            source_group = self._slots[source_instance].outputs[type_name]
            target_group = self._slots[target_instance].inputs[type_name]
            feeds[target_instance].setdefault(type_name, (target_group, []))[1].append(
                (source_group.values, source_group.names.index(source_port),
                 target_group.names.index(target_port)))
        for slot in self._slots.values():
            slot.feeds = list(feeds[slot.spec.name].values())
            slot.read_outputs()
        # Every input group is set once before the first step, whatever its buffer holds.
        for slot in self._slots.values():
            self._send_inputs(slot, force=True)
        self._plan = [(self._slots[s.name], s.rate) for s in self.instances]

    def outputs(self, instance):
        """Buffers of the outputs of ``instance`` read every step: {type: PortGroup}."""
        return self._slots[instance].outputs

    def output_group(self, instance, type_name, names):
        """Resolve any outputs of ``instance`` into a group for :meth:`read_outputs`."""
        return self._slots[instance].spec.handle.port_group(type_name, names)

    def observed_value(self, name):
        """Return ``(buffer, index)`` holding output ``name`` after every step, or None.

        Only outputs read with a connection (see ``observed``) have one; the buffer is
        refreshed after each step of the instance, so read it, do not keep the value.
        """
        instance, port = name.split(".", 1)
        for group in self._slots[instance].output_groups:
            if port in group.names:
                return group.values, group.names.index(port)
        return None

    def read_outputs(self, instance, group):
        """Read a group from :meth:`output_group` now (one batched get); return its values."""
        return self._slots[instance].spec.handle.read(group)

    # ----- stepping --------------------------------------------------------------------------
    def time_of(self, k):
        """Communication point of step ``k``: ``t0 + k * h``."""
        return self.start_time + k * self.base_step

    def step(self, k):
        """Perform macro step ``k`` (from ``t_k`` to ``t_{k+1}``)."""
        t = self.start_time + k * self.base_step
        h = self.base_step
        if self.algorithm == "gauss-seidel":
            for slot, rate in self._plan:
                if k % rate:
                    continue
                self._send_inputs(slot)
                self._do_step(slot, t, rate * h)
                slot.read_outputs()
        else:
            due = [(slot, rate) for slot, rate in self._plan if k % rate == 0]
            for slot, rate in due:
                self._send_inputs(slot)
            for slot, rate in due:
                self._do_step(slot, t, rate * h)
            for slot, rate in due:
                slot.read_outputs()
        self.steps_done = k + 1

    @staticmethod
    def _send_inputs(slot, force=False):
        """Copy connected outputs into the slot's input buffers; set the groups that changed."""
        handle = slot.spec.handle
        for group, pairs in slot.feeds:
            values = group.values
            changed = force
            for source_values, i, j in pairs:
                value = source_values[i]
                if values[j] != value:  # NaN != NaN: a NaN is always sent (and refused)
                    values[j] = value
                    changed = True
            if changed:
                handle.write(group)

    def resend_inputs(self):
        """Set every input group now, changed or not (e.g. after restoring an FMU state)."""
        for slot in self._slots.values():
            self._send_inputs(slot, force=True)

    def refresh_buffers(self):
        """Read every output and input buffer back from the instances.

        After the instances' states were restored (an FMU state of the whole system), the
        buffers must hold what the instances now hold: an input is set only when a new value
        differs from its buffer, so a stale buffer would leave a restored input unchanged.
        """
        for slot in self._slots.values():
            handle = slot.spec.handle
            for group in slot.output_groups + slot.input_groups:
                handle.read(group)

    def _do_step(self, slot, t, step):
        try:
            slot.spec.handle.do_step(t, step)
        except Exception as exc:
            status = getattr(exc, "status", None)
            label = {2: "discard", 3: "error", 4: "fatal"}.get(status, "failure")
            said = slot.spec.handle.last_error()
            raise SimulationError(
                f"instance {slot.spec.name} returned fmi2{label.capitalize()} in doStep at "
                f"t = {t:.6g} s" + (f": {said}" if said else f": {exc}")) from exc

    def terminate(self):
        """Terminate every instance; errors while terminating are ignored."""
        for spec in self.instances:
            try:
                spec.handle.terminate()
            except Exception:  # a failed instance may refuse to terminate; free the others
                pass

    def run(self, stop_time, on_step=None):
        """Step from the start time to ``stop_time``; call ``on_step(k_next, t_next)`` after each.

        Returns the wall time in seconds spent stepping.
        """
        steps = int(round((stop_time - self.start_time) / self.base_step))
        started = wallclock.perf_counter()
        for k in range(self.steps_done, steps):
            self.step(k)
            if on_step is not None:
                on_step(k + 1, self.start_time + (k + 1) * self.base_step)
        return wallclock.perf_counter() - started

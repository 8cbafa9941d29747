"""The master's stepping rules (components/system/master.py), with plain-Python stand-ins for
FMUs (no FMI involved)."""

from types import SimpleNamespace

import pytest

from components.common.errors import ConfigError, SimulationError
from components.system.master import InstanceSpec, Link, Master


class _Group:
    def __init__(self, type_name, names):
        self.type = type_name
        self.names = tuple(names)
        self.values = [0.0] * len(names)

    def __len__(self):
        return len(self.names)


class Recorder:
    """A stand-in FMU: output y = the input u it held during its last step, plus an offset;
    it logs (time, step, u) for every doStep."""

    def __init__(self, name, offset=0.0, fail_at=None):
        self.name = name
        self.offset = offset
        self.fail_at = fail_at
        self.u = 0.0
        self.y = offset
        self.calls = []
        self.reads = 0
        self.writes = []
        self.variables = {
            "u": SimpleNamespace(name="u", causality="input", type="Real"),
            "y": SimpleNamespace(name="y", causality="output", type="Real"),
            "z": SimpleNamespace(name="z", causality="output", type="Real"),
            "n": SimpleNamespace(name="n", causality="output", type="Integer"),
        }

    def instantiate(self, start_time=0.0, stop_time=None, parameters=None):
        self.y = self.offset
        self.z = -self.offset
        self.n = 7

    def port_group(self, type_name, names):
        return _Group(type_name, names)

    def read(self, group):
        self.reads += 1
        for i, name in enumerate(group.names):
            group.values[i] = getattr(self, name)
        return group.values

    def write(self, group):
        self.writes.append(tuple(group.values))
        for name, value in zip(group.names, group.values):
            setattr(self, name, value)

    def do_step(self, time, step):
        if self.fail_at is not None and time >= self.fail_at:
            exc = RuntimeError("refused")
            exc.status = 3
            raise exc
        self.calls.append((round(time, 12), round(step, 12), self.u))
        self.y = self.u + self.offset + 1.0

    def terminate(self):
        pass

    def last_error(self):
        return "input u = nan refused" if self.fail_at is not None else ""


def _chain(algorithm, rate_b=1):
    a, b = Recorder("a", offset=10.0), Recorder("b")
    master = Master([InstanceSpec("a", a), InstanceSpec("b", b, rate=rate_b)],
                    [Link("a.y", "b.u")], 0.1, algorithm)
    master.initialize()
    return master, a, b


def test_gauss_seidel_gives_each_instance_the_outputs_of_those_stepped_before_it():
    master, a, b = _chain("gauss-seidel")
    master.run(0.3)
    # a steps first each macro step; b reads a's output of the same macro step
    assert [c[2] for c in b.calls] == [11.0, 11.0, 11.0]


def test_jacobi_gives_every_instance_the_outputs_at_the_start_of_the_step():
    master, a, b = _chain("jacobi")
    master.run(0.3)
    # at t0 b sees a's initial output (10), afterwards a's output after its previous step
    assert [c[2] for c in b.calls] == [10.0, 11.0, 11.0]


def test_time_is_t0_plus_k_h_and_multirate_instances_step_with_their_own_step():
    master, a, b = _chain("gauss-seidel", rate_b=3)
    master.run(0.9)
    assert [c[0] for c in a.calls] == [round(k * 0.1, 12) for k in range(9)]
    assert [(c[0], c[1]) for c in b.calls] == [(0.0, 0.3), (0.3, 0.3), (0.6, 0.3)]
    assert master.steps_done == 9


def test_inputs_are_held_between_the_steps_of_a_slower_consumer():
    a, b = Recorder("a"), Recorder("b")
    # a feeds back to itself through b, with b three times slower: a sees b's held output
    master = Master([InstanceSpec("a", a), InstanceSpec("b", b, rate=3)],
                    [Link("b.y", "a.u"), Link("a.y", "b.u")], 0.1)
    master.initialize()
    master.run(0.6)
    # k=0: a (u=0) -> y=1, b (u=1) -> y=2; k=1..3: a holds b's 2 (b steps again at k=3, after
    # a), k=3: b (u=3) -> y=4; k=4, 5: a holds 4. Worked out by hand from y = u + 1.
    assert [c[2] for c in a.calls] == [0.0, 2.0, 2.0, 2.0, 4.0, 4.0]
    assert [c[2] for c in b.calls] == [1.0, 3.0]


def test_a_failing_instance_stops_the_run_naming_instance_time_and_status():
    a, b = Recorder("a"), Recorder("b", fail_at=0.25)
    master = Master([InstanceSpec("a", a), InstanceSpec("b", b)], [Link("a.y", "b.u")], 0.1)
    master.initialize()
    with pytest.raises(SimulationError) as caught:
        master.run(1.0)
    message = str(caught.value)
    assert "instance b" in message and "fmi2Error" in message and "t = 0.3 s" in message
    assert "u = nan" in message
    assert master.steps_done == 3  # the steps before the failure are kept


@pytest.mark.parametrize("algorithm, step", [("rk4", 0.1), ("jacobi", 0.0), ("jacobi", -1.0)],
                         ids=["unknown-algorithm", "zero-step", "negative-step"])
def test_bad_settings_name_the_value_and_the_choices(algorithm, step):
    with pytest.raises(ConfigError) as caught:
        Master([], [], step, algorithm)
    assert repr(algorithm) in str(caught.value) or repr(step) in str(caught.value)


def test_an_input_group_is_set_only_when_a_value_in_it_changed():
    a, b = Recorder("a"), Recorder("b")
    # a (every third base step) and b (every step) feed each other; y = u + 1
    master = Master([InstanceSpec("a", a, rate=3), InstanceSpec("b", b)],
                    [Link("a.y", "b.u"), Link("b.y", "a.u")], 0.1)
    master.initialize()
    master.run(0.9)
    # Worked out by hand: k=0: a(u=0) -> 1, b(u=1) -> 2; k=3: a(u=2) -> 3, b(u=3) -> 4;
    # k=6: a(u=4) -> 5, b(u=5) -> 6. Each group is set once at initialisation (the initial
    # outputs, 0), then only when its value changed: b at k = 0, 3, 6 only; a at k = 3, 6.
    assert b.writes == [(0.0,), (1.0,), (3.0,), (5.0,)]
    assert a.writes == [(0.0,), (2.0,), (4.0,)]
    assert [c[2] for c in b.calls] == [1.0] * 3 + [3.0] * 3 + [5.0] * 3
    master.resend_inputs()  # e.g. after restoring an FMU state: sent whether changed or not
    assert b.writes[-1] == (5.0,) and len(b.writes) == 5


def test_a_nan_is_always_sent_so_that_the_fmu_can_refuse_it():
    a, b = Recorder("a"), Recorder("b")
    master = Master([InstanceSpec("a", a), InstanceSpec("b", b)], [Link("a.y", "b.u")], 0.1)
    master.initialize()
    a.offset = float("nan")  # from now on a.y = nan at every step
    master.run(0.3)
    assert len(b.writes) == 4 and all(w[0] != w[0] for w in b.writes[1:])


def test_observed_outputs_ride_along_with_the_connected_reads_of_their_type():
    master, a, b = _chain("gauss-seidel")
    observed = Master([InstanceSpec("a", a), InstanceSpec("b", b)], [Link("a.y", "b.u")], 0.1,
                      observed=["a.z", "a.n", "b.y"])
    observed.initialize()
    reads_before = a.reads
    observed.run(0.2)
    assert a.reads - reads_before == 2  # one Real get per step of a, z included
    values, index = observed.observed_value("a.z")
    assert values[index] == -10.0
    # a.n (Integer) and b.y have no connected read of their type: read on request instead
    assert observed.observed_value("a.n") is None and observed.observed_value("b.y") is None


def test_refreshed_buffers_hold_what_restored_instances_hold():
    a, b = Recorder("a"), Recorder("b")
    master = Master([InstanceSpec("a", a), InstanceSpec("b", b)], [Link("a.y", "b.u")], 0.1)
    master.initialize()
    master.run(0.2)   # a.y = 1 after each step, so b.u was set to 1 once
    writes = len(b.writes)
    # restore b as it was before any step (an FMU state): u = 0, while the buffer still says 1
    b.u = 0.0
    master.refresh_buffers()
    master.step(2)
    # the buffer was read back as 0, so the new value 1 differs and is sent again
    assert len(b.writes) == writes + 1 and b.calls[-1][2] == 1.0

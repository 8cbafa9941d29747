"""Round trips through sonotrack's FMI binary: a String parameter reads back what was set, and
an FMU state restores the state machine with the model (a refused step can be retried).
"""

import pytest

from tests.support.fmi_binary import Host

pytestmark = pytest.mark.integration


def test_string_parameter_reads_back_what_was_set(extracted):
    folder, description = extracted["WheelController"]
    host = Host(folder, description)
    host.slave.setupExperiment(startTime=0.0)
    host.slave.enterInitializationMode()
    host.slave.setString([host.refs["mode"]], ["pid"])
    assert host.slave.getString([host.refs["mode"]]) == [b"pid"]
    host.slave.exitInitializationMode()
    assert host.slave.getString([host.refs["mode"]]) == [b"pid"]
    assert host.slave.getTypesPlatform() == "default"
    assert host.slave.getVersion() == "2.0"
    host.slave.terminate()
    host.free()


def test_instance_state_round_trip_restores_the_step_that_was_refused(probe):
    from fmpy.fmi1 import FMICallException

    folder, description = probe
    host = Host(folder, description)
    host.initialize()
    host.slave.doStep(0.0, 0.01)
    saved = host.slave.getFMUstate()
    host.slave.setInteger([host.refs["action"]], [5])
    with pytest.raises(FMICallException):
        host.slave.doStep(0.01, 0.01)
    host.slave.setFMUstate(saved)  # back to stepComplete with count 1
    host.slave.freeFMUstate(saved)
    host.slave.setInteger([host.refs["action"]], [0])
    host.slave.doStep(0.01, 0.01)
    assert host.slave.getInteger([host.refs["count"]]) == [2]
    host.slave.terminate()
    host.free()

"""The SoundSource slave without building it: outputs before and after the path, units."""

import pytest

from components.source.fmu import SoundSource


def variables(slave):
    return {node.get("name"): node for node in slave.to_xml().find("ModelVariables")}


def test_source_slave_outputs_start_pose_before_stepping_and_end_after():
    slave = SoundSource(instance_name="s")
    slave.path = "straight"
    slave.exit_initialization_mode()
    assert (slave.x, slave.y, slave.emitting) == (0.0, 1.0, True)
    for k in range(3200):
        slave.do_step(k * 0.01, 0.01)
    assert (slave.x, slave.y, slave.vx, slave.vy) == pytest.approx((0.0, 7.0, 0.0, 0.0))
    assert slave.emitting is False
    names = variables(slave)
    assert names["emitting"].get("variability") == "discrete"
    assert names["vy"].find("Real").get("unit") == "m/s"

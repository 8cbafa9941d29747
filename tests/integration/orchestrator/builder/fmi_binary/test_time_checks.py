"""Time and step checks of sonotrack's FMI binary, in every FMU.

A communication point that is NaN or infinite, or a step size that is not positive and finite,
is fmi2Error with a message naming the call, the argument and the value (never fmi2OK, never
fmi2Fatal), and the same goes for fmi2SetupExperiment's start and stop times. The check is in
the C layer, so every FMU refuses alike; afterwards fmi2Reset gives an instance that steps.
"""

import math

import pytest

from tests.support.fmi_binary import NAMES, Host, expect_error
from tests.support.fmu_checks import DRIVES

pytestmark = pytest.mark.integration

NAN, INF = math.nan, math.inf

# case -> (the call on an initialised slave, with the FMU's step h; words of the error line)
BAD_STEPS = {
    "time_nan": (lambda s, h: s.doStep(NAN, h), ("fmi2DoStep", "currentCommunicationPoint = nan")),
    "time_inf": (lambda s, h: s.doStep(INF, h), ("fmi2DoStep", "currentCommunicationPoint = inf")),
    "time_minus_inf": (lambda s, h: s.doStep(-INF, h),
                       ("fmi2DoStep", "currentCommunicationPoint = -inf")),
    "step_zero": (lambda s, h: s.doStep(0.0, 0.0), ("fmi2DoStep", "communicationStepSize = 0 ")),
    "step_negative": (lambda s, h: s.doStep(0.0, -h),
                      ("fmi2DoStep", "communicationStepSize = -", "positive and finite")),
    "step_nan": (lambda s, h: s.doStep(0.0, NAN), ("fmi2DoStep", "communicationStepSize = nan")),
    "step_inf": (lambda s, h: s.doStep(0.0, INF), ("fmi2DoStep", "communicationStepSize = inf")),
}
BAD_SETUPS = {
    "start_nan": (dict(startTime=NAN), ("fmi2SetupExperiment", "startTime = nan")),
    "start_inf": (dict(startTime=INF), ("fmi2SetupExperiment", "startTime = inf")),
    "stop_before_start": (dict(startTime=1.0, stopTime=0.5),
                          ("fmi2SetupExperiment", "stopTime = 0.5", "startTime = 1")),
    "stop_nan": (dict(startTime=0.0, stopTime=NAN), ("fmi2SetupExperiment", "stopTime = nan")),
}


def _step_again(host, name):
    """After fmi2Reset: initialise and take one good step (fmi2OK, or fmpy would raise)."""
    h, _ = DRIVES[name]
    host.slave.reset()
    host.slave.setupExperiment(startTime=0.0)
    host.slave.enterInitializationMode()
    host.slave.exitInitializationMode()
    host.slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=h)


@pytest.mark.parametrize("case", list(BAD_STEPS), ids=list(BAD_STEPS))
@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_bad_communication_point_or_step_size_is_an_error_naming_the_call(extracted, name, case):
    folder, description = extracted[name]
    call, words = BAD_STEPS[case]
    h, _ = DRIVES[name]
    host = Host(folder, description, name=f"{name}_{case}")
    host.initialize()
    expect_error(host, lambda: call(host.slave, h), *words)
    _step_again(host, name)
    host.free()


@pytest.mark.parametrize("case", list(BAD_SETUPS), ids=list(BAD_SETUPS))
@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_bad_start_or_stop_time_is_an_error_naming_the_call(extracted, name, case):
    folder, description = extracted[name]
    arguments, words = BAD_SETUPS[case]
    host = Host(folder, description, name=f"{name}_{case}")
    expect_error(host, lambda: host.slave.setupExperiment(**arguments), *words)
    _step_again(host, name)
    host.free()

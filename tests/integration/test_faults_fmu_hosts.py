"""The FMUs apply their own fault schedule: fmpy's own master, no sonotrack orchestrator."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from components.common.faults import Fault, encode_schedule

pytestmark = pytest.mark.integration


def test_localizer_fmu_applies_its_schedule_in_fmpy(fmu_paths):
    schedule = encode_schedule([Fault("mic_dead", 0.3, 0.6, channel="M3")])
    heading = np.pi / 2
    signals = np.array([(0.0, 0.5, 2.0, True, 0.0, 0.0, heading),
                        (2.0, 0.5, 2.0, True, 0.0, 0.0, heading)],
                       dtype=[("time", float), ("source_x", float), ("source_y", float),
                              ("emitting", bool), ("robot_x", float), ("robot_y", float),
                              ("robot_heading", float)])
    result = simulate_fmu(str(fmu_paths["AcousticLocalizer"]), stop_time=1.0,
                          output_interval=0.1, step_size=0.01, input=signals,
                          start_values={"fault_schedule": schedule},
                          output=["fix_status", "valid", "faults_active", "measurement_id"])
    by_time = {round(float(row["time"]), 2): (int(row["fix_status"]), bool(row["valid"]),
                                               int(row["faults_active"])) for row in result}
    # the fix of instant k*0.1 shows after that step: t = 0.31 .. 0.61 for instants 0.3 .. 0.5
    assert [by_time[t][0] for t in (0.2, 0.4, 0.5, 0.6, 0.7, 0.8)] == [0, 10, 10, 10, 0, 0]
    assert [bool(by_time[t][1]) for t in (0.2, 0.4, 0.7)] == [True, False, True]
    assert by_time[0.5][2] == 1 and by_time[0.8][2] == 0


def test_bad_schedule_is_refused_at_initialisation_with_its_field(fmu_paths):
    from fmpy.fmi1 import FMICallException

    bad = '[{"kind":"mic_dead","start":0,"channel":"M4"}]'
    messages = []
    with pytest.raises(FMICallException):
        simulate_fmu(str(fmu_paths["AcousticLocalizer"]), stop_time=0.1, step_size=0.01,
                     start_values={"fault_schedule": bad},
                     logger=lambda *args: messages.append(args[-1]))
    text = " ".join(m.decode() if isinstance(m, bytes) else str(m) for m in messages)
    assert "fault_schedule[0].channel" in text and "M1, M2, M3" in text, text

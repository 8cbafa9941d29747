"""`verify` end to end: builds the RobotPlant FMU, steps it through fmpy, writes the report."""

import json

import pytest

from components.plant import PlantParameters
from orchestrator.verification import linear_wheel_model, verify

pytestmark = pytest.mark.integration


def _compliance_bound(p, voltage):
    """Largest rim-minus-ground speed the tyre's compliance can add in the step [m/s].

    The TF is rigid (rim speed = ground speed). The plant's tyre transmits ``F = c N s`` with
    slip ``s = (rim - ground) / d``, ``d <= |rim|``, so ``rim - ground <= F |rim| / (c N)``.
    The rim force is largest at the start, ``F <= (m/2) a0`` with ``a0 = v_final / tau``,
    and ``|rim| <= v_final``: the bound is ``(m/2) v_final^2 / (tau c N)`` (5.3 mm/s at 2 V).
    """
    linear = linear_wheel_model(p)
    v_final = voltage * linear.dc_gain
    _, tau = linear.time_constants
    normal = 0.5 * p.mass * p.gravity
    return 0.5 * p.mass * v_final ** 2 / (tau * p.slip_stiffness * normal)


def test_verify_writes_the_report_and_the_fmu_follows_the_tf(tmp_path):
    report = verify(tmp_path, grid_size=3, step_voltage=2.0)
    for name in ("verification.json", "verification.md", "pole_map.png", "step_responses.png",
                 "fmu_vs_tf.png"):
        assert (tmp_path / name).is_file(), name
        assert (tmp_path / name).stat().st_size > 0
    figures = json.loads((tmp_path / "verification.json").read_text())
    assert figures["checks"]["routh_roots_agreement"] == "9/9"
    assert figures["checks"]["boundary_max_relative_difference"] < 1e-6
    markdown = (tmp_path / "verification.md").read_text()
    assert "## Verdict" in markdown and "Built RobotPlant FMU" in markdown

    fmu = report.figures["fmu_step"]
    bound = _compliance_bound(PlantParameters(), 2.0)
    default, fine, stiff = fmu["runs"]
    # Defaults: within the tyre-compliance bound of the rigid TF (measured ~0.85 mm/s).
    assert default["max_abs_difference_m_s"] < bound
    # A finer substep does not change it (it is not integration error) ...
    assert fine["max_abs_difference_m_s"] == pytest.approx(default["max_abs_difference_m_s"],
                                                           rel=0.05)
    # ... a 100x stiffer tyre divides it by ~100: the rest of the plant is the TF.
    assert stiff["max_abs_difference_m_s"] < default["max_abs_difference_m_s"] / 50
    # Time constants: 63.2 % times agree to one part in a hundred.
    assert default["fmu_t63_s"] == pytest.approx(fmu["tf_t63_s"], rel=0.01)
    assert default["left_right_max_difference_m_s"] < 1e-9

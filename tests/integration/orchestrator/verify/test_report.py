"""`verify` end to end: builds the FMUs, runs every check, writes JSON, Markdown and HTML.

And the FMU checks flip when the FMU is not the model: a plant with another armature
resistance, a controller with another gain.
"""

import json
import re

import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from orchestrator.report.html import embedded_image_sources
from orchestrator.verify import (
    WheelLoopModel, closed_loop_fmu_comparison, compliance_bound, controller_fmu_comparison,
    fmu_step_comparison, load_requirements, verify,
)
from orchestrator.verify import checks as C
from tests.support.html_render import ChromiumUnavailable, chromium_path, inspect_report

pytestmark = pytest.mark.integration

REQ = load_requirements()


@pytest.fixture(scope="module")
def report(tmp_path_factory, fmu_dir):
    out = tmp_path_factory.mktemp("verify")
    return verify(out, grid_size=3, step_voltage=2.0, fmu_dir=fmu_dir), out


def test_verify_writes_the_reports_with_checks_and_verdicts(report):
    result, out = report
    for name in ("verification.json", "verification.md", "verification.html", "pole_map.png",
                 "step_responses.png", "fmu_vs_tf.png", "stability_region.png",
                 "bode_corners.png", "root_locus.png", "robustness.png", "closed_loop_fmus.png",
                 "gain_factor_edges.png"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    data = json.loads((out / "verification.json").read_text())
    names = [c["name"] for c in data["checks"]]
    for required in ("routh_vs_roots", "surface_stable", "gain_margin", "phase_margin",
                     "step_response", "pid_baseline", "plant_fmu_vs_tf", "controller_fmu_vs_law",
                     "closed_loop_fmus_vs_tf", "paper_gain_box", "robust_stability_fgs_pd",
                     "robust_stability_x4_fgs_pd", "robust_stability_x4_pid",
                     "robust_steady_state_pd", "robust_steady_state_pid",
                     "routh_gives_paper_bounds", "fgs_pd_overshoot_vs_pid"):
        assert required in names, required
    for check in data["checks"]:
        assert set(check) >= {"name", "requirement", "measured", "passed", "verdict", "why"}
    failed = sum(1 for c in data["checks"] if c["verdict"] == "FAIL")
    assert data["summary"]["exit_status"] == failed == result.exit_status()
    assert result.exit_status(strict=True) == failed + data["summary"]["warnings"]
    # The FMU checks pass on the real FMUs.
    verdicts = {c["name"]: c["passed"] for c in data["checks"]}
    assert verdicts["plant_fmu_vs_tf"] and verdicts["controller_fmu_vs_law"]
    assert verdicts["closed_loop_fmus_vs_tf"]
    markdown = (out / "verification.md").read_text()
    assert "## Checks" in markdown and "Sign convention" in markdown
    assert "## The PD form" in markdown and "|z|" not in markdown.split("## The PD form")[1]
    assert "![" in markdown and "](stability_region.png)" in markdown
    assert str(out) not in markdown
    # The largest stable plant-gain factor, and every warning, stated in the text.
    assert ("FGS-PD corners (weakest corner): stable up to x3.67 plant gain at tau x0.5 "
            "(kp 4.8, kd 0.24)") in markdown
    # the off-nominal requirements: which design meets what, first, and each requirement
    summary = markdown.split("## Contents")[0]
    assert ("FGS-PD, default form: meets settling, load recovery, ramp lag, creep, limit cycle, "
            "slip chatter (all six).") in summary
    assert "FGS-PD, paper form: meets none" in summary
    assert "## Off-nominal requirements" in markdown
    for name in ("off_nominal_settling", "load_step_recovery", "ramp_lag", "no_creep",
                 "no_limit_cycle", "no_slip_chatter"):
        for design in ("default", "paper", "pid", "default_uncommissioned"):
            assert f"{name}_{design}" in names
    assert verdicts["off_nominal_settling_default"] and verdicts["no_creep_default"]
    assert verdicts["no_slip_chatter_default"]
    # the same design told RobotPlant's constants on every wheel: what commissioning buys
    assert not verdicts["off_nominal_settling_default_uncommissioned"]
    assert not verdicts["no_slip_chatter_default_uncommissioned"]
    # the answer first: the summary (counts, then each finding), the contents, the checks
    assert markdown.index("## Summary") < markdown.index("## Contents") < markdown.index(
        "## Checks")
    assert "`" not in (out / "verification.html").read_text()   # no raw markup for readers
    assert "`fgs_pd_overshoot_vs_pid`" in markdown.split("## Figures")[0]
    assert len(data["figures"]["gain_factor_edges"]["sets"]) == 6


def test_plant_fmu_follows_the_tf_within_the_compliance_bound(report):
    fmu = report[0].figures["fmu_step"]
    bound = compliance_bound(PlantParameters(), 2.0)
    default, fine, stiff = fmu["runs"]
    assert default["max_abs_difference_m_s"] < bound
    # A finer substep does not change it (it is not integration error) ...
    assert fine["max_abs_difference_m_s"] == pytest.approx(default["max_abs_difference_m_s"],
                                                           rel=0.05)
    # ... a 100x stiffer tyre divides it by ~100: the rest of the plant is the TF.
    assert stiff["max_abs_difference_m_s"] < default["max_abs_difference_m_s"] / 50
    assert default["fmu_t63_s"] == pytest.approx(fmu["tf_t63_s"], rel=0.01)
    assert default["left_right_max_difference_m_s"] < 1e-9


def test_html_is_self_contained_and_renders_with_every_figure(report):
    result, out = report
    page = (out / "verification.html").read_text()
    sources = embedded_image_sources(page)
    assert len(sources) == len(result.captions) >= 8
    assert all(s.startswith("data:image/png;base64,") for s in sources)
    assert not re.search(r"(?:src|href)=\"(?:https?:|//|/|file:)", page)
    assert str(out) not in page and "e = v_ref - v_meas" in page
    if chromium_path() is None:
        pytest.skip("chromium not installed (make chromium needs apt and root); checked "
                    "instead that every image is embedded PNG data")
    try:
        seen = inspect_report(out / "verification.html", screenshot=out / "verification.png")
    except ChromiumUnavailable as exc:
        pytest.skip(f"chromium did not render: {exc}")
    assert seen["images"] == [len(sources), len(sources)]
    assert seen["summary_top"] is not None and seen["summary_top"] < 300
    assert seen["contents"] and seen["anchors"] > 5 and seen["broken_anchors"] == []
    assert seen["verdict_cells"] >= len(result.checks) and seen["unclassed_verdicts"] == []


def test_plant_fmu_check_fails_for_another_resistance(fmu_dir):
    p = PlantParameters()
    run = fmu_step_comparison(p, voltage=2.0, duration=2.0, step=0.02, fmu_dir=fmu_dir,
                              fmu_overrides={"motor_resistance": 1.5 * p.motor_resistance})
    check = C.check_plant_fmu_vs_tf(run, compliance_bound(p, 2.0), REQ["plant_fmu_vs_tf"])
    assert not check.passed and check.verdict == "FAIL"


def test_controller_fmu_check_fails_for_another_gain(fmu_dir):
    run = controller_fmu_comparison(dict(DEFAULTS), modes=("fgs_pd",), samples=30,
                                    fmu_dir=fmu_dir, fmu_overrides={"kp_max": 5.0})
    check = C.check_controller_fmu_vs_law(run, REQ["controller_fmu_vs_law"])
    assert not check.passed
    assert run["runs"]["fgs_pd"]["max_voltage_difference_v"] > 0.01


def test_closed_loop_fmu_check_fails_for_another_gain(fmu_dir):
    model = WheelLoopModel()
    run = closed_loop_fmu_comparison(model, dict(DEFAULTS), [("pd", 3.0, 0.3, 1.0)],
                                     duration=0.6, fmu_dir=fmu_dir,
                                     fmu_overrides={"pd_kp": 6.0})
    check = C.check_closed_loop_fmus_vs_tf(run, REQ["closed_loop_fmus_vs_tf"])
    assert not check.passed
    assert run["points"][0]["max_difference_fraction_of_step"] > 0.05

"""Closed loop on the RobotPlant core, paper Case 1: FGS-PD against the CPID baseline."""

import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("control")
pytest.importorskip("components.plant")

_PATH = Path(__file__).resolve().parents[4] / "benchmarks" / "wheel_loop.py"
_spec = importlib.util.spec_from_file_location("wheel_loop", _PATH)
wheel_loop = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(wheel_loop)


@pytest.fixture(scope="module")
def results():
    configs = {name: wheel_loop.CONFIGS[name]
               for name in ("fgs_pd", "fgs_pd_paper", "fgs_pd_pure", "pid")}
    return wheel_loop.compare(configs)


_CLAIM_NOT_SUPPORTED = (
    "Paper claim not supported on the right wheel: with the second-order (ROS2) plant "
    "integration, the pure PD overshoots 3.345 % against 3.301 % for PID with feedforward; both "
    "are set by the encoder-quantisation limit cycle, not by a transient (docs/control.md). The "
    "earlier pass came from the first-order plant's integration error. Reported, not tuned.")


_TRIM_ADDS_OVERSHOOT = (
    "Paper claim not supported in the paper form (with its integral trim, docs/control.md): "
    "the trim integrates the ramp lag and overshoots by it, FGS-PD 2.61 / 4.44 % against "
    "2.19 / 3.30 % for the PID (benchmarks/wheel_loop.py). Reported, not tuned.")


@pytest.mark.parametrize("form,side", [
    ("fgs_pd_pure", "left"),
    pytest.param("fgs_pd_pure", "right",
                 marks=pytest.mark.xfail(strict=True, reason=_CLAIM_NOT_SUPPORTED)),
    pytest.param("fgs_pd_paper", "left", marks=pytest.mark.xfail(strict=True,
                                                                 reason=_TRIM_ADDS_OVERSHOOT)),
    pytest.param("fgs_pd_paper", "right", marks=pytest.mark.xfail(strict=True,
                                                                  reason=_TRIM_ADDS_OVERSHOOT)),
    # the default form: the reference model leaves no ramp lag to integrate
    ("fgs_pd", "left"), ("fgs_pd", "right"),
], ids=["pure-left", "pure-right", "paper-left", "paper-right", "default-left",
        "default-right"])
def test_fgs_pd_overshoots_no_more_than_pid(results, form, side):
    assert (results[form][side]["overshoot_percent"]
            <= results["pid"][side]["overshoot_percent"])


@pytest.mark.parametrize("form", ["fgs_pd", "fgs_pd_paper"], ids=["default", "paper"])
@pytest.mark.parametrize("side", ["left", "right"], ids=["left", "right"])
def test_fgs_pd_cruise_error_within_one_encoder_quantum(results, form, side):
    # Feedforward + integral: no steady-state error beyond the encoder's quantisation, whose
    # quantum at a 20 ms window is 2 pi 0.06 / 728 / 0.02 = 25.9 mm/s.
    quantum = 2 * 3.141592653589793 * 0.06 / 728 / 0.02
    metrics = results[form][side]
    assert abs(metrics["mean_cruise_error_m_s"]) < 0.1 * quantum
    assert metrics["dither_pp_m_s"] < quantum

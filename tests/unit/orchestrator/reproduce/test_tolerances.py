"""Monte Carlo draws of the reproduction study: the tolerance file, bands, pairing, ranges."""

import numpy as np
import pytest

from components.common.errors import ConfigError
from orchestrator.reproduce.tolerances import (Tolerance, draw_point, load_tolerances,
                                               monte_carlo_points, run_seed, unit_draws)

DEFAULTS = {"plant.mu": 0.8, "plant.mass": 4.5, "plant.motor_resistance": 2.4,
            "plant.wheel_radius": 0.06, "localizer.snr_db": 20.0,
            "plant.torque_constant": 0.01808, "plant.back_emf_constant": 0.01808,
            "plant.v_supply": 11.1, "plant.coulomb_friction": 0.0,
            **{f"localizer.mic_{m}_{d}": 0.0 for m in ("left", "centre", "right")
               for d in ("along", "across")},
            "localizer.adc_skew_left": 0.0, "localizer.adc_skew_right": 0.0}


def test_shipped_tolerances_have_a_band_and_a_justification_each():
    tolerances = load_tolerances()
    assert {n for t in tolerances for n in (t.parameter, *t.linked)} == set(DEFAULTS)
    for t in tolerances:
        assert len(t.justification) > 40
        assert sum(x is not None for x in (t.relative, t.absolute, t.range)) == 1


def test_linked_parameters_share_one_factor_and_a_range_ignores_the_nominal():
    tolerances = load_tolerances()
    points = monte_carlo_points(tolerances, DEFAULTS, {}, 400)
    kt = np.array([p["plant.torque_constant"] for p in points])
    ke = np.array([p["plant.back_emf_constant"] for p in points])
    assert np.array_equal(kt, ke)                       # one constant, one factor
    assert kt.min() >= 0.01808 * 0.9 and kt.max() <= 0.01808 * 1.1
    assert kt.std() > 0.01808 * 0.04                    # varied: sd of U(-10 %, 10 %) 5.8 %
    dry = np.array([p["plant.coulomb_friction"] for p in points])
    assert dry.min() >= 0.0 and dry.max() <= 0.009 and dry.mean() == pytest.approx(0.0045,
                                                                                    abs=5e-4)
    supply = np.array([p["plant.v_supply"] for p in points])
    assert supply.min() >= 9.9 and supply.max() <= 12.6
    # a broken link (independent draws) would differ run by run
    broken = [Tolerance("plant.torque_constant", relative=0.1, justification="x"),
              Tolerance("plant.back_emf_constant", relative=0.1, justification="x")]
    drawn = monte_carlo_points(broken, DEFAULTS, {}, 5)
    assert any(p["plant.torque_constant"] != p["plant.back_emf_constant"] for p in drawn)


@pytest.mark.parametrize("text, message", [
    ('[parameters."plant.mu"]\nrelative = 0.2\n', "no justification"),
    ('[parameters."plant.mu"]\nrelative = 0.2\nabsolute = 1\njustification = "x"\n',
     "exactly one of relative, absolute, range"),
    ('[parameters."plant.mu"]\nrange = [0.5, 0.1]\njustification = "x"\n', "low < high"),
    ('[parameters."plant.mu"]\nabsolute = 0.1\nlinked = ["plant.x"]\njustification = "x"\n',
     "with a relative band only"),
    ('[parameters."plant.mu"]\nrelative = 1.5\njustification = "x"\n', r"relative = 1.5"),
    ('[parameters."plant.mu"]\nrelativ = 0.2\njustification = "x"\n', "unknown field"),
    ('[parameters.mu]\nrelative = 0.2\njustification = "x"\n', "instance.parameter"),
    ("[parameters\n", "not valid TOML"),
], ids=["no-justification", "both", "bad-range", "linked-absolute", "too-wide", "typo",
        "no-instance", "bad-toml"])
def test_bad_tolerance_files_name_file_and_field(tmp_path, text, message):
    path = tmp_path / "tol.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as info:
        load_tolerances(path)
    assert "tol.toml" in str(info.value)


def test_draws_stay_in_their_bands_and_fill_them_uniformly():
    tolerances = load_tolerances()
    points = monte_carlo_points(tolerances, DEFAULTS, {}, 4000)
    mu = np.array([p["plant.mu"] for p in points])
    snr = np.array([p["localizer.snr_db"] for p in points])
    assert mu.min() >= 0.6 and mu.max() <= 1.0
    assert snr.min() >= 15.0 and snr.max() <= 25.0
    # uniform on [0.6, 1.0]: mean 0.8, sd 0.4 / sqrt(12) = 0.1155 (5 sd of the mean: 0.009)
    assert mu.mean() == pytest.approx(0.8, abs=0.01)
    assert mu.std() == pytest.approx(0.4 / np.sqrt(12), rel=0.05)
    assert [p["seed"] for p in points[:3]] == [1, 2, 3]


def test_run_i_of_two_cells_shares_its_draws_and_seed():
    tolerances = load_tolerances()
    pid = monte_carlo_points(tolerances, DEFAULTS, {"controller_left.mode": "pid"}, 5)
    fgs = monte_carlo_points(tolerances, DEFAULTS, {"controller_left.mode": "fgs_pd"}, 5)
    for a, b in zip(pid, fgs):
        assert {k: v for k, v in a.items() if k != "controller_left.mode"} == \
            {k: v for k, v in b.items() if k != "controller_left.mode"}
    assert pid[0]["plant.mass"] != pid[1]["plant.mass"]
    assert unit_draws(tolerances, 0, study_seed=1) != unit_draws(tolerances, 0, study_seed=0)
    assert run_seed(0, 1) != run_seed(0, 0)


def test_a_cell_setting_a_varied_parameter_is_the_nominal_of_its_band():
    tolerances = load_tolerances()
    low = monte_carlo_points(tolerances, DEFAULTS, {"plant.mu": 0.05}, 200)
    mu = np.array([p["plant.mu"] for p in low])
    assert 0.0375 <= mu.min() and mu.max() <= 0.0625


def test_a_draw_outside_the_valid_range_is_refused():
    tolerances = [Tolerance("plant.mu", relative=0.25, justification="test")]
    with pytest.raises(ConfigError, match=r"plant.mu \+-25 % around 0.8 draws .* outside the "
                                          r"valid range \[0.7, None\]"):
        for index in range(50):
            draw_point(tolerances, {"plant.mu": 0.8}, index, ranges={"plant.mu": (0.7, None)})
    with pytest.raises(ConfigError, match="no nominal value"):
        draw_point(tolerances, {}, 0)

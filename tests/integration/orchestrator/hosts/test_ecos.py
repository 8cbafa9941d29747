"""The committed SystemStructure.ssd in other hosts: libcosim with no step size, and ecos.

Both are compared with our Jacobi master (both step every instance from the previous step's
outputs), on the multi-rate steps the .ssd's step hints give.
"""

import csv
import math
import shutil

import fmpy
import numpy as np
import pytest

from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT
from orchestrator.run.runner import run_scenario
from orchestrator.scenario import scenario_from_dict
from orchestrator.ssp import read_ssd

from orchestrator.hosts.ecos import ecos_binary, read_ecos_csv, run_ecos
from tests.support.fmu_checks import DRIVES

pytestmark = pytest.mark.integration

SSD = REPO_ROOT / "fmus" / "SystemStructure.ssd"
NAMES = list(FMU_PACKAGES)


@pytest.fixture(scope="module")
def system_dir(fmu_dir, tmp_path_factory):
    """The committed .ssd beside freshly built FMUs, as a user would lay them out."""
    folder = tmp_path_factory.mktemp("system")
    for name in NAMES:
        shutil.copy2(fmu_dir / f"{name}.fmu", folder)
    shutil.copy2(SSD, folder / "SystemStructure.ssd")
    return folder


def _our_jacobi_run(ssd, stop_time, out_dir):
    """Our master on the .ssd alone: its parameter values, its step hints, Jacobi."""
    system = read_ssd(ssd)
    scenario = scenario_from_dict({
        "name": "portable", "system": str(ssd), "stop_time": stop_time,
        "base_step": system.base_step,
        "steps": {c.name: c.step_size_hint for c in system.components},
        "seed": 1, "parameters": {}, "master": "jacobi",
    })
    result = run_scenario(scenario, out_dir, progress=False, plots=False,
                          record_interval=system.base_step)
    with open(result.results_csv) as f:
        return list(csv.DictReader(f))


def test_libcosim_runs_the_ssd_with_no_step_size_like_our_jacobi_master(system_dir, tmp_path):
    from orchestrator.hosts.libcosim import run_libcosim_ssd

    stop = 5.0
    columns = ["plant.x", "plant.y", "plant.heading", "source.x", "source.y",
               "localizer.distance", "localizer.bearing", "planner.v_ref_left",
               "controller_left.voltage", "controller_right.voltage"]
    ssd = system_dir / "SystemStructure.ssd"
    _, rows = run_libcosim_ssd(ssd, None, stop, columns)   # step from osp:FixedStepAlgorithm
    theirs = np.array(rows)
    ours_rows = _our_jacobi_run(ssd, stop, tmp_path / "ours")[1:]   # libcosim: after each step
    ours = np.array([[float(r[c]) for c in columns] for r in ours_rows])
    assert theirs.shape == ours.shape == (500, len(columns))
    assert np.ptp(ours[:, columns.index("plant.y")]) > 0.5, "the robot must move"
    # Compare where every instance has just finished a step (multiples of the slowest, 20 ms).
    # In between, a 20 ms instance's outputs are those of its step end in our recorder and the
    # previous ones in libcosim's observer; what the instances exchange is the same (the 10 ms
    # localizer's outputs agree at every row).
    slowest = max(c.step_size_hint for c in read_ssd(ssd).components)
    ratio = int(round(slowest / read_ssd(ssd).base_step))
    common = np.arange(ratio - 1, len(ours), ratio)
    assert float(np.max(np.abs(ours[common] - theirs[common]))) <= 1e-12
    fast = [columns.index("localizer.distance"), columns.index("localizer.bearing")]
    assert float(np.max(np.abs(ours[:, fast] - theirs[:, fast]))) <= 1e-12


# ----- ecos ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def ecos(tmp_path_factory):
    binary, reason = ecos_binary(tmp_path_factory.mktemp("ecos"))
    if binary is None:
        print(f"ecos skipped: {reason}")
        pytest.skip(f"ecos cannot run here: {reason}")
    return binary


def _fmpy_outputs(path, step, stop_time):
    result = fmpy.simulate_fmu(str(path), stop_time=stop_time, step_size=step,
                               output_interval=step)
    return {name: result[name] for name in result.dtype.names}


# ecos's CSV prints Reals with std::to_string: six decimals.
_CSV_RESOLUTION = 1e-6


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_ecos_runs_each_fmu_like_fmpy(ecos, fmu_paths, tmp_path, name):
    step = DRIVES[name][0]
    stop = 40 * step   # ecos divides by zero (SIGFPE) in its progress report below 10 steps
    completed, csv_path = run_ecos(ecos, fmu_paths[name], stop, step, tmp_path)
    assert completed.returncode == 0, completed.stderr[-2000:] + completed.stdout[-2000:]
    theirs = read_ecos_csv(csv_path)
    ours = _fmpy_outputs(fmu_paths[name], step, stop)
    outputs = [v.name for v in fmpy.read_model_description(str(fmu_paths[name])).modelVariables
               if v.causality == "output" and v.type in ("Real", "Integer", "Boolean")]
    rows = len(theirs["time"])
    assert rows >= 39
    np.testing.assert_allclose(theirs["time"], ours["time"][:rows], atol=1e-9)
    for output in outputs:
        mine = np.asarray(ours[output][:rows], dtype=float)
        other = np.asarray(theirs[f"instance.{output}"], dtype=float)
        assert np.max(np.abs(mine - other)) <= _CSV_RESOLUTION, output


def test_ecos_runs_the_ssd_like_our_jacobi_master(ecos, system_dir, tmp_path):
    stop, system = 3.0, read_ssd(SSD)
    completed, csv_path = run_ecos(ecos, system_dir, stop, system.base_step, tmp_path / "ecos",
                                   parameter_set=system.parameter_set_name)
    assert completed.returncode == 0, completed.stderr[-2000:] + completed.stdout[-2000:]
    theirs = read_ecos_csv(csv_path)
    # the one parameter set brings both the String path and the Integer seed
    assert set(theirs["source.path"]) == {"s_curve"}
    assert set(theirs["localizer.seed"]) == {1}
    ours = _our_jacobi_run(system_dir / "SystemStructure.ssd", stop, tmp_path / "ours")
    rows = len(theirs["time"])
    # ecos adds the step to its clock (t += h), so depending on rounding it stops at the stop
    # time or one step before it (2 s at 0.01 s ends at 1.99)
    assert len(ours) - 1 <= rows <= len(ours)
    np.testing.assert_allclose(theirs["time"], [float(r["time"]) for r in ours[:rows]],
                               atol=1e-9)
    compared = 0
    for column in ours[0]:
        if column == "time" or column not in theirs:
            continue
        mine = np.array([float(r[column]) if r[column] not in ("True", "False")
                         else float(r[column] == "True") for r in ours[:rows]])
        other = np.asarray(theirs[column], dtype=float)
        assert np.max(np.abs(mine - other)) <= _CSV_RESOLUTION, column
        compared += 1
    assert compared >= 40
    travelled = math.hypot(theirs["plant.x"][-1], theirs["plant.y"][-1])
    assert travelled > 0.3, "the robot must move for the comparison to mean anything"


def test_ecos_without_the_parameter_set_runs_the_fmu_defaults(ecos, system_dir, tmp_path):
    """What a user gets when omitting --parameterSet: no system parameter applied (README)."""
    completed, csv_path = run_ecos(ecos, system_dir, 0.2, 0.01, tmp_path)
    assert completed.returncode == 0, completed.stderr[-2000:]
    theirs = read_ecos_csv(csv_path)
    defaults = {v.name: v.start for v in fmpy.read_model_description(
        str(system_dir / "SoundSource.fmu")).modelVariables}
    assert set(theirs["source.path"]) == {defaults["path"]} != {"s_curve"}

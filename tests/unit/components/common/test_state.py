"""FMU state snapshots (components/common/state.py): numpy is optional, and exact where used."""

import json
import subprocess
import sys

import numpy as np

from components.common.state import restore, snapshot


def _loaded_after(code):
    """The modules a fresh interpreter has loaded after running ``code``."""
    completed = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys\nprint(' '.join(sorted(sys.modules)))"],
        capture_output=True, text=True, timeout=120, check=True)
    return set(completed.stdout.split())


def test_importing_state_does_not_load_numpy():
    loaded = _loaded_after("import components.common.state")
    assert "components.common.state" in loaded  # the import did run
    assert not {name for name in loaded if name == "numpy" or name.startswith("numpy.")}


def test_the_cores_that_need_no_numpy_snapshot_and_restore_without_loading_it():
    """RobotPlant's and CurvaturePlanner's slaves through a state round trip, numpy never
    loaded: their portable FMUs carry none (docs/fmi_binary.md, "Which models need numpy")."""
    loaded = _loaded_after(
        "import json\n"
        "from components.common.state import restore, snapshot\n"
        "from components.plant.fmu import RobotPlant\n"
        "from components.planner.fmu import CurvaturePlanner\n"
        "for cls in (RobotPlant, CurvaturePlanner):\n"
        "    slave = cls(instance_name='s')\n"
        "    slave.exit_initialization_mode()\n"
        "    slave.do_step(0.0, 0.005)\n"
        "    state = slave._fmu_state_from_bytes(slave._fmu_state_to_bytes(\n"
        "        slave._get_fmu_state()))\n"
        "    slave._set_fmu_state(state)\n")
    assert "components.plant.fmu" in loaded and "components.planner.fmu" in loaded
    assert not {name for name in loaded if name == "numpy" or name.startswith("numpy.")}


class _Holder:
    pass


def test_numpy_arrays_scalars_and_generators_round_trip_bit_for_bit():
    holder = _Holder()
    holder.array = np.array([[0.1, -2.5e-300], [np.pi, 1 / 3]])
    holder.ints = np.arange(5, dtype=np.int32)
    holder.scalar = np.float64(0.1) + np.float64(0.2)
    holder.count = np.int64(7)
    holder.flag = np.bool_(True)
    holder.rng = np.random.default_rng(23)
    holder.rng.normal(size=3)
    holder.nested = {"a": (np.float32(1.5), [np.int8(-3)])}
    saved = json.loads(json.dumps(snapshot(holder)))
    expected_draws = holder.rng.normal(size=4)

    target = _Holder()
    target.rng = np.random.default_rng(0)
    same_generator = target.rng
    restore(target, saved)
    assert target.array.dtype == np.float64 and target.array.shape == (2, 2)
    assert target.array.tobytes() == holder.array.tobytes()
    assert target.ints.dtype == np.int32 and target.ints.tolist() == [0, 1, 2, 3, 4]
    assert target.scalar == 0.30000000000000004 and type(target.scalar) is float
    assert target.count == 7 and type(target.count) is int
    assert target.flag is True
    assert target.nested == {"a": (1.5, [-3])}
    assert target.rng is same_generator  # restored in place
    assert target.rng.normal(size=4).tobytes() == expected_draws.tobytes()


def test_plain_values_snapshot_as_before():
    holder = _Holder()
    holder.x, holder.n, holder.ok, holder.name, holder.none = 0.1, 3, False, "w", None
    holder.pair = (1.0, 2)
    saved = snapshot(holder)
    assert saved == {"__object__": {"x": 0.1, "n": 3, "ok": False, "name": "w", "none": None,
                                    "pair": {"__tuple__": [1.0, 2]}}}
    target = _Holder()
    restore(target, json.loads(json.dumps(saved)))
    assert (target.x, target.n, target.ok, target.name, target.none, target.pair) == \
        (0.1, 3, False, "w", None, (1.0, 2))

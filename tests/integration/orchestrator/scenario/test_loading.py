"""Shipped scenarios with one field mutated: a clear refusal, or a run that says what it used.

Hypothesis changes one field of a shipped scenario (top-level field, ``[steps]`` entry,
``[parameters]`` entry, or a new unknown key) to a value of any TOML type, including NaN,
inf, huge, tiny and negative numbers. Every case goes through the CLI's entry point with a time
limit and must end in either

- a non-zero exit with every stderr line naming the scenario file (and the field, parameter
  or instance), no traceback; or
- exit 0 with the run's summary and the parameter values it used printed.

The base scenario is cut to 0.1 s with ``max_steps = 100`` so that a mutated time or step can
never make a case long: more steps than that is itself a refusal. FMUs are loaded only for
cases the schema accepts.
"""

import math
import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from components.common.ranges import show

from tests.support.bad_inputs import run_case

pytestmark = pytest.mark.integration

SCENARIOS = ("s_curve", "straight", "static_case1", "dynamic_case2")
FIELDS = ("stop_time", "base_step", "seed", "master", "max_steps", "name", "outputs", "system")
PARAMETERS = ("plant.mass", "plant.max_substep", "plant.speed_window", "plant.encoder_ppr",
              "source.emit_period", "source.amplitude", "source.mute_at_end", "source.path",
              "localizer.adc_bits", "localizer.method", "localizer.seed", "planner.v_cruise",
              "planner.mode", "controller_left.kp_max", "controller_right.feedforward")
STEPS = ("source", "planner", "plant", "controller_left", "bogus_instance")

NUMBERS = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 1e300, -1e300, 5e-324,
                     1e-9, 1e308]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=1e-3, max_value=10.0),
)
INTEGERS = st.one_of(st.sampled_from([0, -1, 2**31, 2**32 + 10, 2**63 - 1, -2**63]),
                     st.integers(min_value=-10**20, max_value=10**20))
VALUES = st.one_of(NUMBERS, INTEGERS, st.booleans(),
                   st.sampled_from(["", "false", "true", "nan", "magic", "s_curve", "pd",
                                    "waypoints.csv", "plant.x"]),
                   st.text(max_size=12),
                   st.lists(st.integers(0, 3), max_size=2),
                   st.fixed_dictionaries({"k": st.integers(0, 3)}))
MUTATIONS = st.one_of(
    st.tuples(st.just("field"), st.sampled_from(FIELDS)),
    st.tuples(st.just("parameter"), st.sampled_from(PARAMETERS)),
    st.tuples(st.just("step"), st.sampled_from(STEPS)),
    st.tuples(st.just("unknown"), st.sampled_from(["stop_tme", "parameters.plant.masss",
                                                   "solver", "steps.plant_"])),
)


def _toml_char(c):
    if c.isprintable() and c not in '"\\':
        return c
    return f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}"


def _toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return '"' + "".join(_toml_char(c) for c in value) + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"


def _scenario_text(base, kind, key, value):
    """The base scenario with one mutation, as TOML text (top-level fields before tables)."""
    top = {k: v for k, v in base.items() if k not in ("steps", "parameters")}
    top.update(stop_time=0.1, max_steps=100)
    steps = dict(base.get("steps", {}))
    parameters = {}
    for instance, table in base.get("parameters", {}).items():
        for name, item in table.items():
            parameters[f"{instance}.{name}"] = item
    if kind == "field":
        top[key] = value
    elif kind == "parameter":
        parameters[key] = value
    elif kind == "step":
        steps[key] = value
    else:
        section, _, name = key.partition(".")
        if section == "parameters":
            parameters[name] = value
        elif section == "steps":
            steps[name] = value
        else:
            top[key] = value
    lines = [f"{k} = {_toml_value(v)}" for k, v in top.items()]
    lines += ["[steps]"] + [f"{k} = {_toml_value(v)}" for k, v in steps.items()]
    lines += ["[parameters]"] + [f"{k} = {_toml_value(v)}" for k, v in parameters.items()]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def shipped(repo_root):
    import tomllib

    return {name: tomllib.loads((repo_root / "scenarios" / f"{name}.toml").read_text())
            for name in SCENARIOS}


@settings(max_examples=70, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(scenario=st.sampled_from(SCENARIOS), mutation=MUTATIONS, value=VALUES)
def test_a_mutated_scenario_is_refused_clearly_or_runs_saying_what_it_used(
        shipped, fmu_dir, tmp_path_factory, scenario, mutation, value):
    kind, key = mutation
    folder = tmp_path_factory.mktemp("mutation")
    path = folder / f"{scenario}_{kind}.toml"
    path.write_text(_scenario_text(shipped[scenario], kind, key, value))
    result = run_case(["run", str(path), "--quiet", "--out", str(folder / "out"),
                       "--fmu-dir", str(fmu_dir)], limit=60)
    assert not result["timed_out"] and result["escaped"] is None, result
    output = result["stdout"] + result["stderr"]
    assert "Traceback" not in output
    if result["status"] != 0:
        lines = result["stderr"].splitlines()
        assert lines and lines[0].startswith("sonotrack run: error: "), lines
        # every line names the file; the first (or each problem line) names what is wrong
        assert all(path.name in line for line in lines if not line.startswith("  ")
                   or re.match(r"\s+\S+\.toml: ", line)), lines
        assert re.search(r"field '|unknown field|instance \w+ failed|not valid TOML", output)
    else:
        assert "results: " in result["stdout"]
        if kind == "parameter" and not isinstance(value, dict):
            assert f"{key} = {show(value)}" in result["stdout"]

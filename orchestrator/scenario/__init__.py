"""Scenarios: what to run (system, parameter overrides, times, steps, seed, outputs, master).

A scenario is a TOML file (``scenarios/*.toml``) or a plain dict, validated against
:data:`SCHEMA`, a table written as data: field -> type, whether it is required, its default and
its allowed values. Every problem (unknown field, wrong type, bad choice, a step that is not a
multiple of the base step) becomes one line naming the file, the field, the bad value and the
valid choices, and all lines are raised together in one :class:`ConfigError`.

Before any FMU is loaded, the scenario is also checked against its ``.ssd`` (read as XML) and
the valid-range tables of the FMUs it names (``components/<part>/ranges.toml``, the same tables
the FMUs enforce and export as ``min``/``max``): ``[steps]`` names only instances of the system,
every instance's step lies in its FMU's step range, and every parameter value, from the
scenario or bound in the ``.ssd``, has the right type (no bool for a number, no string for a
bool, no float for an integer) and lies in its valid range. FMUs the tables do not know are
checked against their model descriptions by the system layer.

Work is bounded: ``stop_time / base_step`` may not exceed ``max_steps`` (default
:data:`DEFAULT_MAX_STEPS`; raise it in the scenario for a longer run).

Seeds: the master passes ``seed`` to every instance that has a ``seed`` parameter, unless
``parameters`` sets that instance's seed explicitly.

Modules, one concept each:

- :mod:`~orchestrator.scenario.schema`: :data:`SCHEMA`, the per-field checks, the step checks;
- :mod:`~orchestrator.scenario.locations`: where the ``.ssd`` and file-valued parameters are;
- :mod:`~orchestrator.scenario.system_checks`: instances, step ranges and parameter ranges
  against the ``.ssd`` and the FMUs' range tables;
- :mod:`~orchestrator.scenario.faults`: the ``[[faults]]`` schedule;
- :mod:`~orchestrator.scenario.validation`: all of these applied to a dict, every problem at
  once;
- :mod:`~orchestrator.scenario.model`: the validated :class:`Scenario`, built by
  :func:`scenario_from_dict`, and its input hash;
- :mod:`~orchestrator.scenario.loading`: :func:`load_scenario`, a TOML file read and validated;
- :mod:`~orchestrator.scenario.overrides`: ``--set`` and ``--stop-time`` from a command line,
  validated like the file;
- :mod:`~orchestrator.scenario.shipped`: the shipped scenarios, found by name from any folder.

This ``__init__`` re-exports the public names, so ``from orchestrator.scenario import
load_scenario`` is the stable import path.
"""

from .loading import load_scenario
from .locations import default_system_path
from .model import Scenario, scenario_from_dict
from .overrides import apply_overrides, parse_override, parse_value
from .schema import DEFAULT_MAX_STEPS, MASTERS, SCHEMA, STEP_TOLERANCE, Field, parse_seconds
from .shipped import find_scenario, shipped_scenarios
from .system_checks import model_ranges

__all__ = [
    "DEFAULT_MAX_STEPS",
    "MASTERS",
    "STEP_TOLERANCE",
    "Field",
    "SCHEMA",
    "Scenario",
    "apply_overrides",
    "find_scenario",
    "load_scenario",
    "parse_override",
    "parse_value",
    "shipped_scenarios",
    "scenario_from_dict",
    "default_system_path",
    "model_ranges",
    "parse_seconds",
]

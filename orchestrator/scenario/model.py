"""The validated scenario as a value: :class:`Scenario`, its steps, its dict form and its hash.

:func:`scenario_from_dict` (and :func:`~orchestrator.scenario.load_scenario`) build it once the
schema and the checks against its system have passed (:mod:`orchestrator.scenario.validation`);
:meth:`Scenario.to_dict` gives back the dict it reads; :meth:`Scenario.input_hash` is what a sweep
stores runs by.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

from orchestrator.scenario.faults import faults_to_dicts

from .schema import DEFAULT_MAX_STEPS
from .validation import check_scenario

__all__ = ["Scenario", "scenario_from_dict"]


@dataclass(frozen=True)
class Scenario:
    """A validated scenario.

    Attributes
    ----------
    name : str
        Scenario name.
    description : str
        Free text.
    system : pathlib.Path
        Absolute path of the ``.ssd``.
    stop_time : float
        End time in s (the run starts at 0).
    base_step : float
        Master step in s.
    steps : dict of str to float
        Communication step per instance in s, each an integer multiple of ``base_step``;
        instances not listed step every ``base_step``.
    seed : int
        Given to every instance that has a ``seed`` parameter (unless ``parameters`` sets it).
    parameters : dict of str to value
        Overrides keyed ``"instance.parameter"``.
    outputs : list of str
        ``"instance.port"`` to record; empty means every output.
    master : str
        ``"gauss-seidel"`` or ``"jacobi"``.
    max_steps : int
        Largest number of base steps accepted (a bound on the work, not a result input).
    faults : tuple of (str, Fault)
        ``(target instance, fault)`` per ``[[faults]]`` entry (:mod:`orchestrator.scenario.faults`).
    source : str
        Where the scenario came from (file path or ``"<dict>"``); not part of equality.
    """

    name: str
    description: str
    system: Path
    stop_time: float
    base_step: float
    steps: dict[str, float]
    seed: int
    parameters: dict[str, object]
    outputs: list[str]
    master: str
    max_steps: int = DEFAULT_MAX_STEPS
    faults: tuple = ()
    source: str = field(default="<dict>", compare=False)

    def __hash__(self):
        # The dict fields make the generated hash fail; the canonical JSON is hashable.
        return hash(json.dumps(self.to_dict(), sort_keys=True))

    def step(self, instance):
        """Communication step of ``instance`` in s (``base_step`` unless listed in ``steps``)."""
        return self.steps.get(instance, self.base_step)

    def step_ratio(self, instance):
        """How many base steps one step of ``instance`` spans (an integer >= 1)."""
        return round(self.step(instance) / self.base_step)

    @property
    def step_count(self):
        """Number of base steps from 0 to ``stop_time``."""
        return round(self.stop_time / self.base_step)

    def to_dict(self):
        """Return a plain, JSON-serialisable dict that :func:`scenario_from_dict` reads back."""
        return {
            "name": self.name,
            "description": self.description,
            "system": str(self.system),
            "stop_time": self.stop_time,
            "base_step": self.base_step,
            "steps": dict(sorted(self.steps.items())),
            "seed": self.seed,
            "parameters": dict(sorted(self.parameters.items())),
            "outputs": list(self.outputs),
            "master": self.master,
            "max_steps": self.max_steps,
            # only when there are faults, so a scenario without any hashes as it always did
            **({"faults": faults_to_dicts(self.faults)} if self.faults else {}),
        }

    def with_overrides(self, **changes):
        """Return a validated copy with some fields changed, e.g. for a sweep.

        ``parameters`` and ``steps`` are merged into the existing tables (so a sweep over one
        parameter keeps the others); every other field is replaced.

        Examples
        --------
        >>> fast = scenario.with_overrides(parameters={"planner.v_cruise": 0.4}, seed=7)  # doctest: +SKIP
        """
        data = self.to_dict()
        for key, value in changes.items():
            if key in ("parameters", "steps") and isinstance(value, dict):
                data[key] = {**data[key], **value}
            else:
                data[key] = value
        return scenario_from_dict(data, source=f"{self.source} with overrides")

    def input_hash(self, extra=None):
        """SHA-256 hex digest of everything in the scenario that can change a run's result.

        The name and description are left out; the ``.ssd`` enters by the SHA-256 of its
        content (its path if it is missing), so the same scenario hashes alike in any checkout.
        FMU contents are outside the scenario: pass their digests in ``extra`` (any
        JSON-serialisable value) to include them.
        """
        data = self.to_dict()
        del data["name"], data["description"], data["max_steps"]
        system = Path(data.pop("system"))
        data["system_sha256"] = (hashlib.sha256(system.read_bytes()).hexdigest()
                                 if system.is_file() else str(system))
        if extra is not None:
            data["extra"] = extra
        text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()


def scenario_from_dict(data, source="<dict>", base_dir=None, allow_outside=False):
    """Validate a scenario given as a dict (as TOML would give it).

    Parameters
    ----------
    data : dict
        Fields of :data:`~orchestrator.scenario.SCHEMA`.
    source : str
        Name used in error messages (a file path, or ``"<dict>"``).
    base_dir : str or pathlib.Path, optional
        Directory that a relative ``system`` is resolved from, and whose ``../fmus`` holds the
        default system; without it, the current directory and the repository's ``fmus/``.
        File-valued parameters (``source.path = "waypoints.csv"``) resolve from it too and
        must stay inside it (:mod:`orchestrator.files.paths`).
    allow_outside : bool
        Accept file-valued parameters that lead outside ``base_dir``.

    Returns
    -------
    Scenario

    Raises
    ------
    ConfigError
        Listing every problem, one per line (see
        :func:`~orchestrator.scenario.validation.check_scenario`).
    """
    return Scenario(**check_scenario(data, source=source, base_dir=base_dir,
                                     allow_outside=allow_outside))

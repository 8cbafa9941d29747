"""Monte Carlo draws: physical tolerances from a data file, a seed per run, valid ranges.

``orchestrator/data/tolerances.toml`` lists each varied parameter with its band (relative or
absolute) and the justification. Run ``i`` of the study draws every parameter uniformly in its
band from a generator seeded by ``(study_seed, i)`` and runs with scenario seed
``run_seed(i, study_seed)``, whichever cell it belongs to: two cells' run ``i`` share the
physics and the localizer noise seed (common random numbers), so their difference is paired.
"""

import math
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError

__all__ = ["Tolerance", "load_tolerances", "unit_draws", "run_seed", "draw_point",
           "monte_carlo_points"]


@dataclass(frozen=True)
class Tolerance:
    """One varied parameter: ``nominal * (1 + relative u)``, ``nominal + absolute u`` or
    ``low + (high - low) (u + 1) / 2`` for an absolute ``range`` (a band that does not sit
    around the nominal, e.g. dry friction whose nominal is 0), ``u`` uniform in [-1, 1].
    ``linked`` parameters get the same relative factor (one physical constant that two
    parameters state, e.g. a motor's torque and back-EMF constants)."""

    parameter: str
    relative: float = None
    absolute: float = None
    range: tuple = None
    linked: tuple = ()
    justification: str = ""

    def value(self, nominal, u):
        """The drawn value for a nominal and a unit draw ``u`` in [-1, 1]."""
        if self.relative is not None:
            return float(nominal) * (1.0 + self.relative * u)
        if self.range is not None:
            low, high = self.range
            return low + (high - low) * 0.5 * (u + 1.0)
        return float(nominal) + self.absolute * u

    def band(self):
        """The band as text, e.g. ``"+-25 %"``, ``"+-5"`` or ``"0 to 0.009"``."""
        if self.relative is not None:
            text = f"+-{100 * self.relative:g} %"
            return text + "".join(f", with {name}" for name in self.linked)
        if self.range is not None:
            return f"{self.range[0]:g} to {self.range[1]:g}"
        return f"+-{self.absolute:g}"


def load_tolerances(path=None):
    """Read the tolerance table.

    Parameters
    ----------
    path : path-like, optional
        A TOML file; default ``orchestrator/data/tolerances.toml`` (package data).

    Returns
    -------
    list of Tolerance

    Raises
    ------
    ConfigError
        Naming the file and field: unreadable file, bad TOML, a parameter without exactly one
        of ``relative`` / ``absolute`` / ``range``, a bad ``range`` or ``linked``, a band that is not a finite number >= 0 (relative < 1),
        or a missing justification.
    """
    where = "orchestrator/data/tolerances.toml" if path is None else str(path)
    try:
        text = (resources.files("orchestrator").joinpath("data/tolerances.toml").read_text()
                if path is None else Path(path).read_text())
        data = tomllib.loads(text)
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read the tolerances ({exc})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML ({exc})") from exc
    problems, tolerances = [], []
    for name, entry in data.get("parameters", {}).items():
        field = f"{where}: parameters.\"{name}\""
        if "." not in name:
            problems.append(f"{field}: expected instance.parameter")
            continue
        kinds = [k for k in ("relative", "absolute", "range") if k in entry]
        unknown = sorted(set(entry) - {"relative", "absolute", "range", "linked",
                                       "justification"})
        if unknown:
            problems.append(f"{field}: unknown field(s) {', '.join(unknown)}; valid: "
                            "relative, absolute, range, linked, justification")
        if len(kinds) != 1:
            problems.append(f"{field}: needs exactly one of relative, absolute, range")
            continue
        band = entry[kinds[0]]
        linked = entry.get("linked", [])
        if kinds[0] == "range":
            if (not isinstance(band, list) or len(band) != 2
                    or not all(_number(v) for v in band) or not band[0] < band[1]):
                problems.append(f"{field}.range = {band!r}: must be [low, high], finite "
                                "numbers with low < high")
                continue
            band = (float(band[0]), float(band[1]))
        else:
            limit = 1.0 if kinds[0] == "relative" else math.inf
            if not _number(band) or not 0.0 <= band < limit:
                problems.append(f"{field}.{kinds[0]} = {band!r}: must be a number in "
                                f"[0, {limit:g})")
                continue
            band = float(band)
        if linked and (kinds[0] != "relative" or not isinstance(linked, list)
                       or not all(isinstance(n, str) and "." in n for n in linked)):
            problems.append(f"{field}.linked = {linked!r}: a list of instance.parameter "
                            "names, with a relative band only")
            continue
        if not str(entry.get("justification", "")).strip():
            problems.append(f"{field}: no justification")
            continue
        tolerances.append(Tolerance(name, **{kinds[0]: band}, linked=tuple(linked),
                                    justification=" ".join(entry["justification"].split())))
    if not data.get("parameters"):
        problems.append(f"{where}: no [parameters.\"instance.parameter\"] tables")
    if problems:
        raise ConfigError("; ".join(problems))
    return tolerances


def _number(value):
    return (not isinstance(value, bool) and isinstance(value, (int, float))
            and math.isfinite(value))


def unit_draws(tolerances, index, study_seed=0):
    """Uniform draws in [-1, 1] for run ``index``, one per tolerance (in file order)."""
    generator = np.random.default_rng(np.random.SeedSequence([int(study_seed), int(index)]))
    return {t.parameter: float(u) for t, u in
            zip(tolerances, generator.uniform(-1.0, 1.0, len(tolerances)))}


def run_seed(index, study_seed=0):
    """Scenario seed (localizer noise) of run ``index``."""
    return 1 + int(index) + 1000 * int(study_seed)


def draw_point(tolerances, nominals, index, study_seed=0, ranges=None):
    """Parameter values of run ``index`` around the given nominals.

    Parameters
    ----------
    tolerances : list of Tolerance
    nominals : dict
        ``instance.parameter`` -> nominal value (the cell's own value or the FMU default).
    index : int
        Run index within the cell.
    study_seed : int
        Seed of the whole study.
    ranges : dict, optional
        ``instance.parameter`` -> ``(min, max)`` valid range (None for an open side).

    Returns
    -------
    dict
        ``instance.parameter`` -> value, plus ``"seed"``.

    Raises
    ------
    ConfigError
        If a nominal is missing or a drawn value leaves the parameter's valid range.
    """
    point, problems = {}, []
    draws = unit_draws(tolerances, index, study_seed)
    for t in tolerances:
        for name in (t.parameter, *t.linked):
            if name not in nominals:
                problems.append(f"tolerance {name}: no nominal value (unknown parameter?)")
                continue
            value = t.value(nominals[name], draws[t.parameter])
            low, high = (ranges or {}).get(name, (None, None))
            if (low is not None and value < low) or (high is not None and value > high):
                problems.append(f"tolerance {name} {t.band()} around {nominals[name]:g} "
                                f"draws {value:g}, outside the valid range [{low}, {high}]")
            point[name] = value
    if problems:
        raise ConfigError("; ".join(problems))
    point["seed"] = run_seed(index, study_seed)
    return point


def monte_carlo_points(tolerances, defaults, cell_parameters, runs, study_seed=0, ranges=None):
    """The sweep points of one cell: its own overrides plus the draws of runs ``0..runs-1``.

    A parameter the cell sets itself (e.g. a low ``plant.mu``) is the nominal of its band.
    """
    varied = {name for t in tolerances for name in (t.parameter, *t.linked)}
    nominals = {**defaults, **{k: v for k, v in cell_parameters.items() if k in varied}}
    return [{**cell_parameters, **draw_point(tolerances, nominals, i, study_seed, ranges)}
            for i in range(runs)]

"""The one JSON policy: non-finite numbers become null, and no NaN token is ever written."""

import json
import math
from pathlib import PurePosixPath

import numpy as np
import pytest

from orchestrator.files import json_policy
from orchestrator.files.json_policy import dumps, json_ready


def _strict_loads(text):
    """Parse as a strict JSON reader would: NaN, Infinity and -Infinity are errors."""
    def refuse(token):
        raise ValueError(f"invalid JSON token {token}")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -math.inf, np.float64("nan"),
                                   np.float32("inf"), np.array(np.nan)],
                         ids=["nan", "inf", "-inf", "numpy-nan", "numpy-float32-inf",
                              "numpy-0d-nan"])
def test_every_non_finite_number_is_written_as_null(value):
    data = {"top": value, "list": [1.0, value], "tuple": (value,), "deep": {"x": [{"y": value}]}}
    assert _strict_loads(dumps(data)) == {"top": None, "list": [1.0, None], "tuple": [None],
                                          "deep": {"x": [{"y": None}]}}
    assert dumps(value) == "null"


class _Estimate:
    def to_dict(self):
        return {"mean": float("nan"), "n": np.int64(0)}


def test_report_values_become_plain_json_types():
    data = {"estimate": _Estimate(), "path": PurePosixPath("figures/fig07.png"),
            "array": np.array([1.5, np.inf]), "flag": np.bool_(True), 3: np.int32(4)}
    assert json_ready(data) == {"estimate": {"mean": None, "n": 0},
                                "path": "figures/fig07.png", "array": [1.5, None],
                                "flag": True, 3: 4}
    assert _strict_loads(dumps(data))["3"] == 4


def test_finite_values_are_written_as_json_dumps_writes_them():
    data = {"a": [0.1, 1e-300, 12345678901234567890, -0.0], "b": {"c": "\u00b5", "d": None},
            "e": np.float64(0.30000000000000004)}
    assert dumps(data, indent=2) == json.dumps(data, indent=2)


def test_a_nan_that_escapes_the_conversion_is_an_error_not_a_token(monkeypatch):
    monkeypatch.setattr(json_policy, "json_ready", lambda value: value)
    with pytest.raises(ValueError, match="not JSON compliant"):
        dumps({"settling_s": float("nan")})


def test_unknown_types_are_refused():
    with pytest.raises(TypeError, match="not JSON serializable"):
        dumps({"x": object()})

"""The test helper tests/support/json_leaves.py names every leaf by its full path and keeps its value.

The summary comparisons in test_run_metrics.py compare two flattenings with each other, so a
helper that dropped or rewrote leaves would make them pass vacuously; this pins it down.
"""

from tests.support.json_leaves import leaves


def test_every_leaf_is_named_by_its_path_and_kept():
    value = {"a": 1.5, "b": {"c": [3, {"d": None}], "e": "x"}, "f": [], "g": {}}
    assert list(leaves(value)) == [(".a", 1.5), (".b.c[0]", 3), (".b.c[1].d", None),
                                   (".b.e", "x")]
    assert list(leaves(7, "top")) == [("top", 7)]

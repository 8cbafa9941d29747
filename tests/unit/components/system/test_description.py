"""The system description the whole-system FMU carries: read back exactly, refused in full."""

import json

import pytest

from components.common.errors import ConfigError
from components.system.description import InstancePlan, SystemDescription


def _description(**changes):
    fields = dict(
        name="demo", base_step=0.01, algorithm="gauss-seidel", stop_time=2.0, seed=4,
        instances=(InstancePlan("source", "SoundSource", "source", 1, {"path": "static",
                                                                      "v_max": 0.1}),
                   InstancePlan("localizer", "AcousticLocalizer", "acoustics", 2, {}, True)),
        links=(("source.x", "localizer.source_x"),),
        robot_position=("localizer.true_distance", "localizer.true_bearing"),
        source_position=("source.x", "source.y"))
    fields.update(changes)
    return SystemDescription(**fields)


def test_json_reads_back_to_the_same_description():
    description = _description(base_step=0.1 + 0.2)   # a float that prints with 17 digits
    again = SystemDescription.from_json(description.to_json())
    assert again == description and again.base_step == 0.1 + 0.2
    assert again.packages == ("source", "acoustics") and again.macro_rate == 2


def test_every_problem_is_named_at_once():
    data = json.loads(_description().to_json())
    data["base_step"] = -0.01
    data["algorithm"] = "rk4"
    data["seed"] = True
    data["instances"][1]["rate"] = 0
    data["instances"][1]["name"] = "source"
    data["links"].append(["nowhere.x", "source.y"])
    with pytest.raises(ConfigError) as caught:
        SystemDescription.from_json(json.dumps(data), source="d.json")
    message = str(caught.value)
    for words in ("d.json", "base_step -0.01", "'rk4'", "seed True", "instances[1].rate 0",
                  "instances[1].name 'source' is repeated", "nowhere.x"):
        assert words in message, words


def test_text_that_is_not_json_or_of_another_format_is_refused():
    with pytest.raises(ConfigError, match="not JSON"):
        SystemDescription.from_json("{", source="d.json")
    data = json.loads(_description().to_json())
    data["format"] = 2
    with pytest.raises(ConfigError, match="format 2 is not 1"):
        SystemDescription.from_json(json.dumps(data))

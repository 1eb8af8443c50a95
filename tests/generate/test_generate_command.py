"""``povagent generate`` writes a dataset and says what it wrote."""

from __future__ import annotations

from typer.testing import CliRunner

from povagent.cli import app


def test_the_generate_command_writes_a_valid_dataset(two_houses):
    from povagent.dataset.validate import validate_dataset

    # the session's two_houses is the command's output (tests/generate/conftest.py); the fixture
    # fails on a non-zero exit, naming the output
    assert "2 houses" in two_houses.output
    assert validate_dataset(two_houses.root) == []


JUDGE_PLUGIN = """
from povagent import hookimpl
from povagent.generate import SurfaceVerdict

class FrontAndUp:
    def __init__(self, up_surface="on the anchor"):
        self.up_surface = up_surface

    def judge(self, request):
        if request.direction == "front":
            return SurfaceVerdict("appropriate", "on the floor")
        if request.direction == "up":
            return SurfaceVerdict("appropriate", self.up_surface)
        return SurfaceVerdict("inappropriate", None)

@hookimpl
def register_judges(register):
    register("front-and-up", FrontAndUp, description="front and up only (a test judge)")
"""


def test_a_judge_registered_by_a_plugin_module_decides_the_directions(tmp_path):
    import json

    plugin = tmp_path / "my_judges.py"
    plugin.write_text(JUDGE_PLUGIN)
    out = tmp_path / "data"
    args = ["generate", "--out", str(out), "--houses", "1", "--seed", "3", "--frames", "2"]
    args += ["--plugin", str(plugin), "--judge", "front-and-up", "--judge-option", "up_surface=on the top"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    generator = json.loads((out / "meta.json").read_text())["generator"]
    assert generator["judge"] == "front-and-up" and generator["judge_options"] == {"up_surface": "on the top"}
    entries = json.loads((out / "artifacts/train_house_00000/train_house_00000.json").read_text())
    assert entries and all(set(e["placements"]) == {"front", "up"} for e in entries)


def test_an_unknown_judge_name_suggests_the_nearest_before_writing_anything(tmp_path):
    from povagent.errors import PluginError

    out = tmp_path / "data"
    result = CliRunner().invoke(app, ["generate", "--out", str(out), "--judge", "physical-rule"])
    assert isinstance(result.exception, PluginError)
    assert "unknown judge 'physical-rule' (did you mean 'physical-rules'?)" in str(result.exception)
    assert not out.exists()


def test_a_judge_given_as_module_colon_name_is_pointed_at_the_plugin_option(tmp_path):
    from povagent.errors import PluginError

    result = CliRunner().invoke(app, ["generate", "--out", str(tmp_path), "--judge", "my_judges:FrontAndUp"])
    assert isinstance(result.exception, PluginError)
    assert "unknown judge 'my_judges:FrontAndUp'" in str(result.exception) and "--plugin my_judges" in str(result.exception)


def test_a_judge_option_without_a_value_is_refused():
    result = CliRunner().invoke(app, ["generate", "--out", "unused", "--judge-option", "model"])
    assert result.exit_code == 2 and "KEY=VALUE" in result.output

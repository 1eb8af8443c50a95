"""``povagent generate`` writes a dataset and says what it wrote."""

from __future__ import annotations

from typer.testing import CliRunner

from povagent.cli import app


def test_the_generate_command_writes_a_valid_dataset(tmp_path):
    from povagent.dataset.validate import validate_dataset

    result = CliRunner().invoke(app, ["generate", "--out", str(tmp_path), "--houses", "1", "--seed", "3", "--frames", "2"])
    assert result.exit_code == 0, result.output
    assert "1 houses" in result.output
    assert validate_dataset(tmp_path) == []


def test_a_judge_named_on_the_command_line_decides_the_directions(tmp_path, monkeypatch):
    import json

    (tmp_path / "my_judges.py").write_text(
        "from povagent.generate import SurfaceVerdict\n"
        "class FrontAndUp:\n"
        "    name = 'front-and-up'\n"
        "    def judge(self, request):\n"
        "        if request.direction == 'front':\n"
        "            return SurfaceVerdict('appropriate', 'on the floor')\n"
        "        if request.direction == 'up':\n"
        "            return SurfaceVerdict('appropriate', 'on the anchor')\n"
        "        return SurfaceVerdict('inappropriate', None)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "data"
    args = ["generate", "--out", str(out), "--houses", "1", "--seed", "3", "--frames", "2"]
    args += ["--judge", "my_judges:FrontAndUp"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert json.loads((out / "meta.json").read_text())["generator"]["judge"] == "front-and-up"
    entries = json.loads((out / "artifacts/train_house_00000/train_house_00000.json").read_text())
    assert entries and all(set(e["placements"]) == {"front", "up"} for e in entries)


def test_a_judge_that_cannot_be_loaded_is_reported_by_name(tmp_path):
    from povagent.errors import PluginError

    result = CliRunner().invoke(app, ["generate", "--out", str(tmp_path), "--judge", "no_such_module:Judge"])
    assert isinstance(result.exception, PluginError) and "no_such_module:Judge" in str(result.exception)

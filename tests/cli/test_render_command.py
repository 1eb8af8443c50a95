"""``povagent render`` writes any camera of a generated house (a frame's camera gives the frame's
bytes) and refuses, in one line, a house whose record no longer describes it and an ``--out``
that cannot take the PNG; ``show-prompt`` of the active strategy prints the tools and the first
turn."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def test_render_of_an_exploration_frame_camera_writes_that_frame(generated_release, tmp_path):
    house = generated_release / "artifacts" / "train_house_00000"
    entry = json.loads((house / "exploration_log.json").read_text())[2]
    cam = entry["camera"]
    out = tmp_path / "view.png"
    result = runner.invoke(app, ["render", str(generated_release), "--house", "train_house_00000",
                                 "--cam-pos", ",".join(str(v) for v in cam["cam_pos"]), "--yaw", str(cam["cam_yaw"]),
                                 "--horizon", str(cam["cam_horizon"]), "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert out.read_bytes() == (house / entry["image_path"]).read_bytes()


def test_render_refuses_a_position_that_is_not_three_numbers(generated_release, tmp_path):
    result = runner.invoke(app, ["render", str(generated_release), "--house", "train_house_00000", "--cam-pos", "1,nan,2",
                                 "--yaw", "0", "--horizon", "0", "--out", str(tmp_path / "x.png")])  # fmt: skip
    assert result.exit_code == 2 and "X,Y,Z" in result.output


def test_show_prompt_of_the_active_strategy_prints_the_tools_and_the_first_turn(generated_release, tmp_path):
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({"dataset": {"path": str(generated_release)}, "backend": "explorer-oracle",
                                        "strategy": {"name": "active", "options": {"max_actions": 5}},
                                        "parser": "active", "output": str(tmp_path / "run")}))  # fmt: skip
    from povagent.dataset.loader import load_dataset

    instance = next(i.id for i in load_dataset(generated_release).instances() if i.id.endswith("/a"))
    result = runner.invoke(app, ["show-prompt", str(pipeline), "--instance", instance, "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    first_turn = result.stdout.split("=== turn 2")[0]
    assert "Image 7:" in first_turn and "Image 8:" not in first_turn  # max_frames 8 by default
    assert "You have 5 actions" in first_turn and '"name": "go_to_frame"' in first_turn


# -- what render refuses, in one line ---------------------------------------------------------------
def _render(dataset, out) -> tuple[int, str]:
    """``render`` of a fixed camera in house 0: (exit code, the one line it printed or raised)."""
    from povagent.errors import PovagentError

    result = runner.invoke(app, ["render", str(dataset), "--house", "train_house_00000", "--cam-pos", "1,0.9,-2",
                                 "--yaw", "30", "--horizon", "30", "--out", str(out)])  # fmt: skip
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        assert isinstance(result.exception, PovagentError), f"traceback: {result.exception!r}"
        message = str(result.exception)
        assert "\n" not in message
        return 2, message
    return result.exit_code, result.output


def _house_copy(generated_release, tmp_path, change=None):
    """House 0 copied under ``tmp_path/gen``, its record passed through ``change``."""
    import shutil

    house = tmp_path / "gen" / "artifacts" / "train_house_00000"
    shutil.copytree(generated_release / "artifacts" / "train_house_00000", house)
    if change is not None:
        record = json.loads((house / "_generated.json").read_text())
        change(record)
        (house / "_generated.json").write_text(json.dumps(record))
    return tmp_path / "gen"


def test_render_refuses_a_record_whose_seed_was_changed_naming_file_and_field(generated_release, tmp_path):
    dataset = _house_copy(generated_release, tmp_path, lambda r: r["options"].update(seed=r["options"]["seed"] + 1))
    code, message = _render(dataset, tmp_path / "view.png")
    assert code == 2 and message.startswith(f"{dataset}/artifacts/train_house_00000/_generated.json: field digest does not match")
    assert not (tmp_path / "view.png").exists()


def test_render_refuses_a_negative_seed_in_one_line(generated_release, tmp_path):
    from povagent.generate.record import generation_digest

    def negative(record):
        record["options"]["seed"] = -1
        record["digest"] = generation_digest(record["index"], record["options"])

    code, message = _render(_house_copy(generated_release, tmp_path, negative), tmp_path / "view.png")
    assert code == 2 and "_generated.json: field options.seed must be a non-negative integer" in message


def test_render_uses_a_record_written_before_digests_as_it_is(generated_release, tmp_path):
    dataset = _house_copy(generated_release, tmp_path, lambda r: r.pop("digest"))
    house = dataset / "artifacts" / "train_house_00000"
    entry = json.loads((house / "exploration_log.json").read_text())[1]
    cam, out = entry["camera"], tmp_path / "view.png"
    result = runner.invoke(app, ["render", str(dataset), "--house", "train_house_00000",
                                 "--cam-pos", ",".join(str(v) for v in cam["cam_pos"]), "--yaw", str(cam["cam_yaw"]),
                                 "--horizon", str(cam["cam_horizon"]), "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert out.read_bytes() == (house / entry["image_path"]).read_bytes()


@pytest.mark.parametrize("where", ["a folder", "an empty path", "an unwritable place"])
def test_an_out_that_cannot_take_the_png_is_one_line_naming_it(generated_release, tmp_path, where):
    out = {"a folder": tmp_path, "an empty path": "", "an unwritable place": "/proc/povagent-render.png"}[where]
    code, message = _render(generated_release, out)
    assert code == 2 and message.startswith("--out ")

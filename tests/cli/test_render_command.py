"""``povagent render`` writes any camera of a generated house (a frame's camera gives the frame's
bytes); ``show-prompt`` of the active strategy prints the tools and the first turn."""

from __future__ import annotations

import json

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

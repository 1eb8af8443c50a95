"""``povagent show-prompt``: the exact messages for one instance, images saved."""

from __future__ import annotations

import re
from pathlib import Path

import yaml
from console_once import console_script_once
from PIL import Image
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import DatasetError

runner = CliRunner()
INSTANCE = "train_house_00000/0/right/a"


def pipeline(tmp_path: Path, mini_root: Path, strategy: str) -> Path:
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "backend": {"name": "center"},
        "strategy": {"name": strategy},
        "output": str(tmp_path / "run"),
    }))
    return path


def show(tmp_path, mini_root, strategy, instance=INSTANCE):
    out = tmp_path / "shown"
    result = runner.invoke(app, ["show-prompt", str(pipeline(tmp_path, mini_root, strategy)), "--instance", instance, "--out", str(out)])
    return result, out


def test_prints_labels_images_with_hashes_then_the_prompt(tmp_path, mini_root):
    result, _ = show(tmp_path, mini_root, "basic")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "--- message 1 (user) ---"
    assert lines[1] == "Image 0:"
    assert lines[2].startswith("[image: Image 0 sha256:") and "512x512" in lines[2]
    assert lines[3] == "Image 1:"
    prompt_start = lines.index(
        "You are the intelligent brain system of a home-assistance robot. You are given first-person perspective images captured during the robot's "
        "exploration of a home."
    )
    assert lines[prompt_start + 1] == ""  # the runner's paragraphs: a blank line between them
    assert lines[prompt_start + 2].startswith("The 3 images above (labeled Image 0 through Image 2)")
    assert "describing where they last saw it.Your mission" in result.stdout  # the runner's text, typo kept
    assert '"max_tokens": 256' in result.stdout and "--- answer schema:" in result.stdout


def test_given_shows_the_image_label_before_the_observer_view(tmp_path, mini_root):
    result, _ = show(tmp_path, mini_root, "basic", instance="train_house_00000/0/right/c")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[1] == "Image:" and lines[2].startswith("[image: observer view sha256:")
    assert lines[3] == "You are the intelligent brain system of a home-assistance robot."


def test_the_marker_note_is_shown_with_the_marked_frames(tmp_path, mini_root):
    result, _ = show(tmp_path, mini_root, "o-plot")
    assert result.exit_code == 0, result.output
    assert ('etc.).\nIn some images, a red circle marks the observer\'s furniture (the object they were working '
            'with at the moment they saw the target object). \n\nSentence: "') in result.stdout


def test_a_model_profile_brings_its_prompts_and_generation_settings(tmp_path, mini_root):
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "model": "molmopoint-8b",
        "strategy": "basic",
        "output": str(tmp_path / "run"),
    }))
    result = runner.invoke(app, ["show-prompt", str(path), "--instance", INSTANCE, "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    assert result.stdout.rstrip().splitlines()[-3] == "Point to the center of the target object."
    path.write_text(path.read_text().replace("molmopoint-8b", "gemini-2.5-flash"))
    result = runner.invoke(app, ["show-prompt", str(path), "--instance", INSTANCE, "--out", str(tmp_path / "shown")])
    assert "--- generation: {}" in result.stdout  # no token limit: the runner set none for Gemini


def test_the_printed_text_is_the_strategy_prompt_verbatim(tmp_path, mini_root, mini_dataset):
    from povagent_plugins.strategies.cot import SpatialCotStrategy

    result, _ = show(tmp_path, mini_root, "spatial-cot")
    assert SpatialCotStrategy().prompt_text(mini_dataset.instance(INSTANCE)) in result.stdout


def test_marked_frames_are_saved_and_flagged(tmp_path, mini_root):
    result, out = show(tmp_path, mini_root, "oa-plot")
    assert result.exit_code == 0, result.output
    saved = sorted(out.glob("*.png"))
    marked = [p for p in saved if "_marked_" in p.name]
    assert len(saved) == 3 and marked
    assert "[image marked: Image 0" in result.stdout
    with Image.open(marked[0]) as im:
        assert (0, 0, 255) in {c for _, c in im.convert("RGB").getcolors(1 << 20)}


def test_an_unknown_instance_suggests_a_near_id(tmp_path, mini_root):
    result, _ = show(tmp_path, mini_root, "basic", instance="train_house_00000/0/rigth/a")
    assert isinstance(result.exception, DatasetError)
    assert "train_house_00000/0/right/a" in str(result.exception)


def test_an_unknown_instance_shows_the_id_format_and_real_ids(tmp_path, mini_root, mini_dataset):
    result, _ = show(tmp_path, mini_root, "basic", instance="x")
    assert isinstance(result.exception, DatasetError)
    message = str(result.exception)
    assert "no instance 'x'" in message and "four parts separated by '/'" in message
    example = message.split("HOUSE/PAIR/DIRECTION/CONDITION, e.g. ", 1)[1].splitlines()[0]
    assert mini_dataset.instance(example) is not None  # an id of this dataset, as it writes them
    shown = [line.strip() for line in message.splitlines() if line.startswith("  ")]
    assert 1 <= len(shown) <= 3 and all(mini_dataset.instance(i) is not None for i in shown)
    assert len({i.split("/")[0] for i in shown}) == 2  # the examples spread over the houses


def test_an_unknown_instance_names_the_part_that_is_wrong(tmp_path, mini_root):
    cases = {
        "train_house_00009/0/right/a": "no house 'train_house_00009' in the dataset",
        "train_house_00000/0/rigth/a": "direction 'rigth' is not one of right, left, front, up",
        "train_house_00000/0/right/d": "condition 'd' is not one of a (Inferred), b (Stated), c (Given)",
        "train_house_00000/7/right/a": "house 'train_house_00000' has no pair '7'",
    }
    for instance, why in cases.items():
        result, _ = show(tmp_path, mini_root, "basic", instance=instance)
        assert why in str(result.exception), (instance, str(result.exception))


def generated_pipeline(tmp_path: Path, dataset: Path) -> Path:
    path = tmp_path / "generated.yaml"
    path.write_text(yaml.safe_dump({"dataset": {"path": str(dataset)}, "backend": "center", "output": str(tmp_path / "run")}))
    return path


def test_the_help_example_is_an_id_as_a_generated_set_writes_them(generated_release):
    from povagent.dataset.loader import load_dataset

    shown = runner.invoke(app, ["show-prompt", "--help"]).stdout
    example = re.search(r"e\.g\.\s+(\S+)", shown).group(1)
    house, pair, direction, condition = example.split("/")
    ids = [i.id for i in load_dataset(generated_release).instances()]
    assert any(i.startswith(f"{house}/{pair}/") for i in ids) and condition in "abc"
    assert direction in {i.split("/")[2] for i in ids}


def test_a_mistyped_id_is_never_offered_back_as_the_example(tmp_path, generated_release):
    mistyped = "train_house_00000/0/right/a"  # the release's pair ids, not a generated set's
    result = runner.invoke(app, ["show-prompt", str(generated_pipeline(tmp_path, generated_release)), "--instance", mistyped])
    message = str(result.exception)
    assert isinstance(result.exception, DatasetError) and message.count(mistyped) == 1  # only where it is quoted
    example = message.split("HOUSE/PAIR/DIRECTION/CONDITION, e.g. ", 1)[1].splitlines()[0]
    assert example.startswith("train_house_00000/pair_")


def test_an_unknown_instance_is_a_message_and_exit_2_from_the_console_script(tmp_path_factory, mini_root):
    # show-prompt of the basic strategy's pipeline, --instance train_house_00000/0/rigth/a
    done = console_script_once(tmp_path_factory, mini_root)["show-prompt"]
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "(did you mean 'train_house_00000/0/right/a'?)" in done.stderr
    assert "ids in this dataset for house train_house_00000:" in done.stderr


def test_an_instance_of_a_house_loading_left_out_says_why_in_one_line(tmp_path, dataset_copy):
    import json

    pairs = dataset_copy / "artifacts" / "train_house_00000" / "train_house_00000.json"
    data = json.loads(pairs.read_text())
    data[0]["stage5"]["right"]["type_a"] = "the book \ud800"  # a lone surrogate: no file can hold it
    pairs.write_text(json.dumps(data))
    result, _ = show(tmp_path, dataset_copy, "basic")
    assert isinstance(result.exception, DatasetError)
    message = str(result.exception)
    assert "\n" not in message and "loading left it out" in message
    assert "train_house_00000.json: $[0].stage5.right.type_a: text holds \\ud800" in message


def test_prints_the_prompt_of_an_instance_of_the_shipped_real_world_demo(tmp_path):
    demo = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"
    result, out = show(tmp_path, demo, "basic", "house_1/kitchen/right/c")
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("--- message 1 (user) ---") and "--- answer schema:" in result.stdout
    assert len(list(out.glob("*.png"))) == 1  # condition C: the observer view, letterboxed

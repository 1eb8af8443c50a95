"""``validate`` finds every planted defect of the broken fixture house, in plain words."""

from __future__ import annotations

import pytest

from povagent.dataset.validate import validate_dataset

BROKEN = "artifacts/train_house_00002"


@pytest.fixture(scope="module")
def problems(mini_root):
    return validate_dataset(mini_root)


def find(problems, file_suffix, path, words):
    return [p for p in problems if p.file.endswith(file_suffix) and p.json_path == path and words in p.message]


def test_the_good_houses_have_no_problem(problems):
    assert not [p for p in problems if "00000" in p.file or "00001" in p.file]


@pytest.mark.parametrize(
    "file_suffix, path, words",
    [
        ("train_house_00002.json", "$[0].stage3.sideways", "unknown direction 'sideways'"),
        ("train_house_00002.json", "$[1]", "required field 'camera' is missing"),
        ("train_house_00002.json", "$[2].object_landmark.raw_metadata.axisAlignedBoundingBox", "'cornerPoints' is missing"),
        ("train_house_00002.json", "$[3].stage5", "direction 'left' has a placement but no sentence"),
        ("train_house_00002.json", "$[3].rgb_path", "'img_from_observer/missing.png' does not exist"),
        ("exploration_log.json", "$[1].image_path", "is 256x256 but its camera is 512x512"),
        ("exploration_log.json", "$[2].image_path", "cannot be decoded"),
        ("exploration_log.json", "$[3].image_path", "'exploration_images/frame_003.png' does not exist"),
        ("per_image_visible_objects.json", "$", "is not valid JSON"),
    ],
)
def test_each_planted_defect_is_found_with_file_path_and_sentence(problems, file_suffix, path, words):
    assert find(problems, file_suffix, path, words), "\n".join(map(str, problems))


def test_exactly_the_planted_defects_are_reported(problems):
    assert len(problems) == 9, "\n".join(map(str, problems))


def test_problem_text_names_file_and_path(problems):
    text = str(find(problems, "exploration_log.json", "$[2].image_path", "decoded")[0])
    assert text.startswith(f"{BROKEN}/exploration_log.json: $[2].image_path: ")


# -- the record of a generated house ----------------------------------------------------------------
def generated_copy(generated_release, tmp_path, change=None):
    """House 0 of the generated set copied under ``tmp_path/gen``, its record passed through ``change``."""
    import json
    import shutil

    house = tmp_path / "gen" / "artifacts" / "train_house_00000"
    shutil.copytree(generated_release / "artifacts" / "train_house_00000", house)
    if change is not None:
        record = json.loads((house / "_generated.json").read_text())
        change(record)
        (house / "_generated.json").write_text(json.dumps(record))
    return tmp_path / "gen"


def test_validate_refuses_a_record_whose_seed_was_changed_by_file_and_field(generated_release, tmp_path):
    root = generated_copy(generated_release, tmp_path, lambda r: r["options"].update(seed=r["options"]["seed"] + 1))
    found = [str(p) for p in validate_dataset(root)]
    assert len(found) == 1 and found[0].startswith("artifacts/train_house_00000/_generated.json: $.digest: does not match"), found


def test_validate_refuses_a_record_with_a_negative_seed(generated_release, tmp_path):
    from povagent.generate.record import generation_digest

    def negative(record):
        record["options"]["seed"] = -3
        record["digest"] = generation_digest(record["index"], record["options"])  # sealed again: the seed rule must hold alone

    found = [(p.json_path, p.message) for p in validate_dataset(generated_copy(generated_release, tmp_path, negative))]
    assert found == [("$.options.seed", "must be a non-negative integer, as every generated house's is (got -3)")]


def test_validate_warns_of_a_record_without_digest_and_says_valid(generated_release, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    root = generated_copy(generated_release, tmp_path, lambda r: r.pop("digest"))
    result = CliRunner().invoke(app, ["validate", str(root)])
    assert result.exit_code == 0 and result.stdout.strip() == f"{root}: valid"
    assert result.stderr.strip() == (
        "warning: artifacts/train_house_00000/_generated.json: $.digest: has no digest (written by an earlier povagent): "
        "its seed and options cannot be checked; `povagent render` and the active mode use it as it is"
    )

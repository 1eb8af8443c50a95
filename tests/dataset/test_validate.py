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

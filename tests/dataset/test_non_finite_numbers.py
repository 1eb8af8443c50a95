"""NaN and Infinity are not numbers a dataset may hold.

Python's ``json`` reads ``NaN``, ``Infinity`` and ``1e999`` (which overflows to infinity)
without complaint; a NaN observer position silently turns the ground truth into "behind the
camera" (where the centre guess scores a perfect 0) and an infinite yaw leaves rows unscored.
``validate`` and loading both reject every non-finite number, naming file and JSON path.
"""

from __future__ import annotations

import pytest

from povagent.dataset.loader import load_dataset
from povagent.dataset.validate import validate_dataset

HOUSE = "train_house_00000"  # one pair (0) with four directions, three exploration frames
NAN, INF = float("nan"), float("inf")


def _set(path_keys, value):
    def change(data):
        node = data
        for k in path_keys[:-1]:
            node = node[k]
        node[path_keys[-1]] = value

    return change


CASES = {
    # name: (file name or None for the pair file, keys to the number, value, JSON path)
    "NaN observer camera position": (None, (0, "camera", "cam_pos", 1), NAN, "$[0].camera.cam_pos[1]"),
    "infinite observer yaw": (None, (0, "camera", "cam_yaw"), INF, "$[0].camera.cam_yaw"),
    "NaN anchor position": (None, (0, "object_landmark", "position", "x"), NAN, "$[0].object_landmark.position.x"),
    "-Infinity bounding-box corner": (
        None,
        (0, "object_landmark", "raw_metadata", "axisAlignedBoundingBox", "cornerPoints", 3, 2),
        -INF,
        "$[0].object_landmark.raw_metadata.axisAlignedBoundingBox.cornerPoints[3][2]",
    ),
    "NaN placement": (None, (0, "placements", "left", "position", "z"), NAN, "$[0].placements.left.position.z"),
    "NaN in a field the loader ignores": (None, (0, "camera", "exposure"), NAN, "$[0].camera.exposure"),
    "infinite exploration yaw": ("exploration_log.json", (1, "camera", "cam_yaw"), INF, "$[1].camera.cam_yaw"),
    "NaN exploration position": ("exploration_log.json", (0, "camera", "cam_pos", 0), NAN, "$[0].camera.cam_pos[0]"),
}


@pytest.fixture(params=CASES.values(), ids=CASES.keys())
def planted(request, editor):
    name, keys, value, path = request.param
    editor.edit(HOUSE, _set(keys, value), name)
    return (name or f"{HOUSE}.json"), path


def test_validate_reports_the_non_finite_number_by_file_and_json_path(dataset_copy, planted):
    file, path = planted
    found = [p for p in validate_dataset(dataset_copy) if p.file.endswith(f"{HOUSE}/{file}") and p.json_path == path]
    assert found, validate_dataset(dataset_copy)
    assert "finite" in found[0].message


def test_loading_rejects_the_non_finite_number_by_file_and_json_path(dataset_copy, planted):
    file, path = planted
    ds = load_dataset(dataset_copy)
    found = [p for p in ds.problems if p.file.endswith(f"{HOUSE}/{file}") and path.startswith(p.json_path)]
    assert found, ds.problems
    assert "finite" in found[0].message and path.removeprefix(found[0].json_path).lstrip(".") in str(found[0])
    # the pair (or, for a frame, the whole house: A/B frame indices must not shift) is not used
    assert not [i for i in ds.instances() if i.house_id == HOUSE and i.pair_id == "0"]


def test_a_number_that_overflows_to_infinity_is_rejected(dataset_copy, editor):
    pairs = editor.path(HOUSE)
    pairs.write_text(pairs.read_text().replace('"cam_yaw": ', '"cam_yaw": 1e999, "was": ', 1))
    assert any("cam_yaw" in p.json_path and "finite" in p.message for p in validate_dataset(dataset_copy))
    assert any("cam_yaw" in str(p) and "finite" in p.message for p in load_dataset(dataset_copy).problems)


def test_meta_json_with_nan_is_reported(dataset_copy):
    (dataset_copy / "meta.json").write_text('{"version": "1", "scale": NaN}')
    assert [p for p in validate_dataset(dataset_copy) if p.file == "meta.json" and p.json_path == "$.scale"]
    assert [p for p in load_dataset(dataset_copy).problems if p.file == "meta.json" and "scale" in str(p)]


def test_the_centre_guess_cannot_score_a_perfect_zero_on_a_nan_observer(dataset_copy, editor):
    # The silent wrong result the rule prevents: with a NaN observer position the GT fell
    # "behind the camera" at (0.5, 0.5) and the centre guess scored 0 on every Given instance.
    editor.edit(HOUSE, _set((0, "camera", "cam_pos", 0), NAN))
    ds = load_dataset(dataset_copy)
    assert ds.instance(f"{HOUSE}/0/left/c") is None

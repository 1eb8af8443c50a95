"""``validate`` and loading refuse an object box no house holds (any side over
``MAX_OBJECT_SIDE_M``): the per-instance geometry is sized by the anchor's box, and a dataset
that passed ``validate`` once made one instance's relation region exhaust memory."""

from __future__ import annotations

from povagent.dataset.loader import load_dataset
from povagent.dataset.release_models import MAX_OBJECT_SIDE_M
from povagent.dataset.validate import validate_dataset

HOUSE = "train_house_00000"


def _set_size(side: float):
    def change(data):
        data[0]["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"]["size"]["x"] = side

    return change


def test_validate_refuses_an_absurd_object_box_by_file_and_field(dataset_copy, editor):
    editor.edit(HOUSE, _set_size(300.0))
    found = [p for p in validate_dataset(dataset_copy) if p.file.endswith(f"{HOUSE}/{HOUSE}.json") and "axisAlignedBoundingBox.size" in p.json_path]
    assert found, validate_dataset(dataset_copy)
    assert f"greater than the maximum of {MAX_OBJECT_SIDE_M}" in found[0].message


def test_loading_leaves_out_the_pair_with_an_absurd_anchor(dataset_copy, editor):
    editor.edit(HOUSE, _set_size(1500.0))
    ds = load_dataset(dataset_copy)
    assert any("axisAlignedBoundingBox.size" in p.json_path for p in ds.problems)
    assert not [i for i in ds.instances() if i.house_id == HOUSE and i.pair_id == "0"]

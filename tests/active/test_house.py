"""A house rebuilt from its record renders every image of the dataset byte for byte, and a
house this generator version did not make is refused with one line."""

from __future__ import annotations

import json
import shutil

import pytest

from povagent.active import house as house_module
from povagent.active.house import check_generated, house_for, render_view
from povagent.errors import DatasetError
from povagent.geometry.camera import Camera


def _camera(record: dict) -> Camera:
    return Camera(tuple(record["cam_pos"]), record["cam_yaw"], record["cam_horizon"], record["fov"],
                  record.get("screen_width", 512), record.get("screen_height", 512))  # fmt: skip


def test_every_exploration_frame_and_observer_view_is_reproduced_byte_for_byte(active_dataset):
    checked = 0
    for folder in sorted((active_dataset / "artifacts").iterdir()):
        for entry in json.loads((folder / "exploration_log.json").read_text()):
            assert render_view(active_dataset, folder.name, _camera(entry["camera"])) == (folder / entry["image_path"]).read_bytes()
            checked += 1
        for pair in json.loads((folder / f"{folder.name}.json").read_text()):
            assert render_view(active_dataset, folder.name, _camera(pair["camera"])) == (folder / pair["rgb_path"]).read_bytes()
            checked += 1
    assert checked >= 2 * 12 + 2


def test_the_public_release_layout_without_a_record_is_refused_in_one_line(mini_root):
    with pytest.raises(DatasetError) as err:
        render_view(mini_root, "train_house_00000", Camera((0, 0.9, 0), 0, 0))
    assert "no readable _generated.json" in str(err.value) and "\n" not in str(err.value)


def test_a_house_of_another_generator_version_is_refused(active_dataset, tmp_path):
    folder = tmp_path / "artifacts" / "train_house_00000"
    folder.mkdir(parents=True)
    record = json.loads((active_dataset / "artifacts" / "train_house_00000" / "_generated.json").read_text())
    record["options"]["version"] = "2"
    (folder / "_generated.json").write_text(json.dumps(record))
    with pytest.raises(DatasetError, match="generator version '2'"):
        check_generated(tmp_path, "train_house_00000")


@pytest.mark.parametrize("name", ["../train_house_00000", "..", "", "a/b"])
def test_a_house_name_leaving_the_dataset_is_refused(active_dataset, name):
    with pytest.raises(DatasetError, match="not a house name"):
        check_generated(active_dataset, name)


def test_the_per_process_house_cache_is_bounded(active_dataset, monkeypatch, tmp_path):
    monkeypatch.setattr(house_module, "CACHE_SIZE", 1)
    copy = tmp_path / "copy"
    shutil.copytree(active_dataset / "artifacts" / "train_house_00001", copy / "artifacts" / "train_house_00001")
    first = house_for(active_dataset, "train_house_00000")
    house_for(copy, "train_house_00001")
    assert len(house_module._CACHE) == 1
    assert house_for(active_dataset, "train_house_00000") is not first  # rebuilt: it had been let go


def test_a_house_whose_record_seed_was_changed_is_refused_naming_the_digest(active_dataset, tmp_path):
    folder = tmp_path / "artifacts" / "train_house_00000"
    folder.mkdir(parents=True)
    record = json.loads((active_dataset / "artifacts" / "train_house_00000" / "_generated.json").read_text())
    record["options"]["seed"] += 1  # the same index of another seed: another house
    (folder / "_generated.json").write_text(json.dumps(record))
    with pytest.raises(DatasetError) as err:
        house_for(tmp_path, "train_house_00000")
    assert str(err.value).startswith(f"{folder / '_generated.json'}: field digest does not match") and "\n" not in str(err.value)

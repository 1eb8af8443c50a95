"""Loading the release layout into houses and instances."""

from __future__ import annotations

import json
import shutil

import pytest

from povagent.dataset import load_dataset
from povagent.errors import DatasetError


def test_good_houses_load_and_the_broken_one_is_reported_not_fatal(mini_dataset):
    assert sorted(mini_dataset.houses) == ["train_house_00000", "train_house_00001"]
    assert any("train_house_00002" in p.file for p in mini_dataset.problems)


def test_strict_loading_raises_naming_the_broken_file(mini_root):
    with pytest.raises(DatasetError, match="train_house_00002"):
        load_dataset(mini_root, strict=True)


def test_one_instance_per_pair_direction_and_condition(mini_dataset):
    # house 0: 4 directions, house 1: 2 directions; three conditions each
    assert len(mini_dataset.instances()) == (4 + 2) * 3


def test_instance_ids_are_house_pair_direction_condition(mini_dataset):
    ids = {i.id for i in mini_dataset.instances()}
    assert "train_house_00000/0/left/a" in ids
    assert "train_house_00001/7/front/c" in ids


def test_inferred_and_stated_show_every_exploration_frame_in_log_order(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/up/a")
    assert [f.image_path for f in inst.frames] == [
        "exploration_images/frame_000.png",
        "exploration_images/frame_001.png",
        "exploration_images/frame_002.png",
    ]
    assert all(f.file.exists() for f in inst.frames)


def test_given_shows_the_observer_view(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/up/c")
    assert [f.image_path for f in inst.frames] == ["img_from_observer/pair_0.png"]
    assert inst.frames[0].camera == inst.observer_camera


def test_sentences_per_condition(mini_dataset):
    a = mini_dataset.instance("train_house_00000/0/left/a").sentence
    b = mini_dataset.instance("train_house_00000/0/left/b").sentence
    c = mini_dataset.instance("train_house_00000/0/left/c").sentence
    assert a == "While replacing the bulb, I spotted the book to the left of the bed."
    assert "floor lamp" in b
    assert c == "The book was to the left of the bed."


def test_sentence_given_as_an_object_is_read(mini_dataset):
    assert mini_dataset.instance("train_house_00000/0/up/c").sentence == "The book was on top of the bed."


def test_numeric_pair_ids_become_strings(mini_dataset):
    assert "0" in mini_dataset.houses["train_house_00000"].pairs


def test_filters_select_conditions_directions_and_houses(mini_dataset):
    got = mini_dataset.instances(conditions=["c"], directions=["front"], houses=["train_house_00001"])
    assert [i.id for i in got] == ["train_house_00001/7/front/c"]


def test_a_missing_dataset_folder_is_a_clear_error(tmp_path):
    with pytest.raises(DatasetError, match="not found"):
        load_dataset(tmp_path / "nope")


def test_a_folder_without_houses_is_a_clear_error(tmp_path):
    with pytest.raises(DatasetError, match="no house folders"):
        load_dataset(tmp_path)


def test_malformed_json_names_the_file_and_skips_only_that_house(mini_root, tmp_path):
    root = tmp_path / "ds"
    shutil.copytree(mini_root, root)
    (root / "artifacts/train_house_00001/train_house_00001.json").write_text("[{,}")
    ds = load_dataset(root)
    assert "train_house_00001" not in ds.houses and "train_house_00000" in ds.houses
    assert any(p.file.endswith("train_house_00001.json") and "not valid JSON" in p.message for p in ds.problems)


def test_extra_keys_are_kept_and_ignored(mini_root, tmp_path):
    root = tmp_path / "ds"
    shutil.copytree(mini_root, root)
    f = root / "artifacts/train_house_00001/train_house_00001.json"
    data = json.loads(f.read_text())
    data[0]["new_release_field"] = {"anything": [1, 2]}
    data[0]["camera"]["near_clip"] = 0.1
    f.write_text(json.dumps(data))
    ds = load_dataset(root)
    assert "7" in ds.houses["train_house_00001"].pairs
    assert not [p for p in ds.problems if "00001" in p.file]


def test_instances_are_built_once_and_shared_by_every_selection(mini_dataset):
    everything = {i.id: i for i in mini_dataset.instances()}
    some = mini_dataset.instances(conditions=["c"], directions=["left"])
    assert some and all(everything[i.id] is i for i in some)

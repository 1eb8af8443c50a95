"""The generated files are a valid POVBench release: the project's validator and loader accept them."""

from __future__ import annotations

import json

from povagent.dataset.loader import load_dataset
from povagent.dataset.release_models import PairEntry
from povagent.dataset.validate import validate_dataset
from povagent.generate.writer import MIN_HIT_PIXELS


def test_the_validator_finds_no_problem(tiny_dataset):
    assert validate_dataset(tiny_dataset.root) == []


def test_every_pair_entry_validates_against_the_release_model(tiny_dataset):
    pairs = tiny_dataset.pairs()
    assert pairs, "the tiny house should yield at least one pair"
    for entry in pairs:
        PairEntry.model_validate(entry)


def test_only_appropriate_directions_are_emitted_with_all_three_sentences(tiny_dataset):
    for entry in tiny_dataset.pairs():
        dirs = set(entry["placements"])
        assert dirs and dirs <= {"right", "left", "front", "up"}
        assert set(entry["stage3"]) == set(entry["stage5"]) == set(entry["stage6"]) == dirs
        assert all(v["verdict"] == "appropriate" for v in entry["stage3"].values())


def test_image_paths_are_relative_to_the_house_folder_and_exist(tiny_dataset):
    log = tiny_dataset.log()
    assert [r["image_path"] for r in log] == [f"exploration_images/frame_{k:03d}.png" for k in range(len(log))]
    for r in log:
        assert (tiny_dataset.house_dir / r["image_path"]).is_file()
    for entry in tiny_dataset.pairs():
        assert (tiny_dataset.house_dir / entry["rgb_path"]).is_file()


def test_exploration_cameras_follow_the_paper(tiny_dataset):
    for r in tiny_dataset.log():
        cam = r["camera"]
        assert cam["cam_pos"][1] == 0.9 and cam["cam_horizon"] == 30 and cam["fov"] == 100


def test_object_hits_are_the_objects_the_instance_mask_shows(tiny_dataset):
    ids = json.loads((tiny_dataset.house_dir / "_render" / "instances.json").read_text())
    for k, record in enumerate(tiny_dataset.log()):
        mask = tiny_dataset.instance(f"frame_{k:03d}")
        values, counts = (a.tolist() for a in __import__("numpy").unique(mask, return_counts=True))
        shown = sorted(ids[str(v)] for v, n in zip(values, counts) if v > 0 and n >= MIN_HIT_PIXELS)
        assert record["object_in_frame_hits"] == shown


def test_per_image_visible_objects_lists_the_types_of_the_hits(tiny_dataset):
    visible = json.loads((tiny_dataset.house_dir / "per_image_visible_objects.json").read_text())
    for record in tiny_dataset.log():
        types = sorted({i.split("|")[0] for i in record["object_in_frame_hits"]})
        assert visible[record["image_path"]] == types


def test_meta_records_the_seed_and_the_counts(tiny_dataset):
    meta = json.loads((tiny_dataset.root / "meta.json").read_text())
    dataset = load_dataset(tiny_dataset.root)
    assert meta["seed"] == 7
    assert meta["counts"]["instances_per_condition"] == len(dataset.instances(conditions=["a"]))

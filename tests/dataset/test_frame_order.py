"""Frames in the official order (povagent/dataset/loader.py): every PNG of ``exploration_images/``
sorted by file name, names containing ``depth`` left out, frame k of an answer being the k-th of
that list, as the authors' runner built its requests and mapped ``selected_image`` back."""

from __future__ import annotations

import json
import shutil

import pytest
from PIL import Image

from povagent.dataset import load_dataset

HOUSE = "train_house_00000"


@pytest.fixture
def release(tmp_path, mini_root):
    """A copy of the fixture holding house 0 only (three frames, frame_000 .. frame_002)."""
    root = tmp_path / "release"
    (root / "artifacts").mkdir(parents=True)
    shutil.copytree(mini_root / "artifacts" / HOUSE, root / "artifacts" / HOUSE)
    return root


def house_dir(root):
    return root / "artifacts" / HOUSE


def log(root) -> list[dict]:
    return json.loads((house_dir(root) / "exploration_log.json").read_text())


def write_log(root, records) -> None:
    (house_dir(root) / "exploration_log.json").write_text(json.dumps(records))


def add_frame(root, name, record_like=0, yaw=None) -> None:
    """A PNG ``name`` and a log record for it (a copy of record ``record_like``)."""
    Image.new("RGB", (512, 512), (10, 20, 30)).save(house_dir(root) / "exploration_images" / name)
    records = log(root)
    record = json.loads(json.dumps(records[record_like]))
    record["image_path"] = f"exploration_images/{name}"
    if yaw is not None:
        record["camera"]["cam_yaw"] = yaw
    write_log(root, records + [record])


def paths(root) -> list[str]:
    ds = load_dataset(root)
    return [f.image_path for f in ds.instance(f"{HOUSE}/0/right/a").frames]


def test_frames_follow_the_file_names_not_the_log(release):
    write_log(release, list(reversed(log(release))))
    add_frame(release, "a_first.png")
    assert paths(release) == [
        "exploration_images/a_first.png",
        "exploration_images/frame_000.png",
        "exploration_images/frame_001.png",
        "exploration_images/frame_002.png",
    ]


def test_each_frame_keeps_its_own_records_camera_and_hits(release):
    write_log(release, list(reversed(log(release))))
    frames = load_dataset(release).instance(f"{HOUSE}/0/right/a").frames
    assert [f.camera.yaw for f in frames] == [0.0, 180.0, 0.0]
    assert [sorted(f.in_frame_hits) for f in frames] == [["Bed|1"], [], ["Bed|1", "FloorLamp|1"]]
    assert [f.index for f in frames] == [0, 1, 2]


def test_depth_maps_and_other_files_are_not_frames(release):
    add_frame(release, "frame_001_depth.png")
    (house_dir(release) / "exploration_images" / "notes.txt").write_text("x")
    add_frame(release, "frame_003.PNG")  # the runner lists *.png only
    assert paths(release) == [f"exploration_images/frame_00{i}.png" for i in range(3)]


def test_a_logged_frame_missing_on_disk_is_not_shown(release):
    (house_dir(release) / "exploration_images" / "frame_001.png").unlink()
    assert paths(release) == ["exploration_images/frame_000.png", "exploration_images/frame_002.png"]


def test_a_frame_without_a_log_record_makes_the_house_unusable_with_a_problem(release):
    Image.new("RGB", (512, 512)).save(house_dir(release) / "exploration_images" / "frame_009.png")
    shutil.copytree(house_dir(release), release / "artifacts" / "train_house_00001")
    (release / "artifacts" / "train_house_00001" / f"{HOUSE}.json").rename(
        release / "artifacts" / "train_house_00001" / "train_house_00001.json"
    )
    (release / "artifacts" / "train_house_00001" / "exploration_images" / "frame_009.png").unlink()
    ds = load_dataset(release)
    assert HOUSE not in ds.houses and "train_house_00001" in ds.houses
    (problem,) = [p for p in ds.problems if HOUSE in p.file]
    assert "exploration_images/frame_009.png" in problem.message


def test_a_repeated_log_path_takes_the_last_record(release):
    records = log(release)
    again = json.loads(json.dumps(records[0]))
    again["camera"]["cam_yaw"] = 90.0
    write_log(release, records + [again])
    frames = load_dataset(release).instance(f"{HOUSE}/0/right/a").frames
    assert len(frames) == 3 and frames[0].camera.yaw == 90.0


def test_a_selected_index_names_the_frame_of_the_same_order(release):
    from povagent.exchange.images import ImageStore
    from povagent_plugins.strategies.basic import BasicStrategy

    add_frame(release, "a_first.png", yaw=45.0)
    inst = load_dataset(release).instance(f"{HOUSE}/0/right/a")
    store = ImageStore()
    request = BasicStrategy().build(inst, store)
    # the k-th image shown is frame k, and frame k is the k-th file name
    assert request.image_hashes()[0] == store.add_file(house_dir(release) / "exploration_images" / "a_first.png").image_hash
    assert inst.frames[0].image_path == "exploration_images/a_first.png" and inst.frames[0].camera.yaw == 45.0

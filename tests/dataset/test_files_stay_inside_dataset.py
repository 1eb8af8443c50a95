"""Every file a dataset names must resolve inside the dataset folder, and nothing else is read.

A dataset is untrusted input: an ``image_path`` or ``rgb_path`` that is absolute, climbs out
with ``../``, or is a symlink leading out of the dataset must never be opened (it would be
base64-sent to a model). ``validate`` reports each escape by file and JSON field; loading
refuses the house, says why, and goes on with the others; ``--strict`` stops.
"""

from __future__ import annotations

import os
import shutil

import pytest
from PIL import Image

from povagent.dataset.loader import load_dataset
from povagent.dataset.validate import validate_dataset
from povagent.errors import DatasetError

HOUSE = "train_house_00001"  # one pair (7), two exploration frames


@pytest.fixture
def outside_png(tmp_path):
    """A readable PNG outside the dataset folder: what a hostile path would leak."""
    path = tmp_path / "secret" / "outside.png"
    path.parent.mkdir()
    Image.new("RGB", (512, 512), (200, 10, 10)).save(path)
    return path


def escape_frame(ed, value):
    ed.edit(HOUSE, lambda log: log[0].update(image_path=value), "exploration_log.json")


def escape_observer_view(ed, value):
    ed.edit(HOUSE, lambda pairs: pairs[0].update(rgb_path=value))


def symlink_frame(ed, target):
    frame = ed.root / "artifacts" / HOUSE / "exploration_images" / "frame_000.png"
    frame.unlink()
    os.symlink(target, frame)


def _absolute(ed, outside):
    escape_frame(ed, str(outside))
    return "exploration_log.json", "$[0].image_path"


def _climbing(ed, outside):
    escape_frame(ed, os.path.relpath(outside, ed.root / "artifacts" / HOUSE))
    return "exploration_log.json", "$[0].image_path"


def _symlink(ed, outside):
    symlink_frame(ed, outside)
    return "exploration_log.json", "$[0].image_path"


def _observer_absolute(ed, outside):
    escape_observer_view(ed, str(outside))
    return f"{HOUSE}.json", "$[0].rgb_path"


def _observer_climbing(ed, outside):
    escape_observer_view(ed, "../../../secret/outside.png")
    return f"{HOUSE}.json", "$[0].rgb_path"


ESCAPES = {
    "absolute image_path": _absolute,
    "image_path climbing with ../": _climbing,
    "image_path through a symlink": _symlink,
    "absolute rgb_path": _observer_absolute,
    "rgb_path climbing with ../": _observer_climbing,
}


@pytest.mark.parametrize("plant", ESCAPES.values(), ids=ESCAPES.keys())
def test_loading_never_opens_a_file_outside_the_dataset(dataset_copy, editor, outside_png, opened_files, plant):
    plant(editor, outside_png)
    ds = load_dataset(dataset_copy)
    for inst in ds.instances():
        assert all(f.file.resolve().is_relative_to(dataset_copy.resolve()) for f in inst.frames)
    assert str(outside_png) not in opened_files


@pytest.mark.parametrize("plant", ESCAPES.values(), ids=ESCAPES.keys())
def test_loading_refuses_the_house_naming_file_and_field_and_goes_on(dataset_copy, editor, outside_png, plant):
    file, field = plant(editor, outside_png)
    ds = load_dataset(dataset_copy)
    assert HOUSE not in ds.houses
    assert "train_house_00000" in ds.houses  # the run goes on with the other houses
    found = [p for p in ds.problems if p.file.endswith(f"{HOUSE}/{file}") and p.json_path == field]
    assert found, ds.problems
    assert "outside the dataset" in found[0].message or "absolute" in found[0].message


@pytest.mark.parametrize("plant", ESCAPES.values(), ids=ESCAPES.keys())
def test_strict_loading_stops_at_an_escape(dataset_copy, editor, outside_png, plant):
    plant(editor, outside_png)
    with pytest.raises(DatasetError, match=HOUSE):
        load_dataset(dataset_copy, strict=True)


@pytest.mark.parametrize("plant", ESCAPES.values(), ids=ESCAPES.keys())
def test_validate_reports_each_escape_by_file_and_field_and_opens_nothing_outside(dataset_copy, editor, outside_png, opened_files, plant):
    file, field = plant(editor, outside_png)
    problems = validate_dataset(dataset_copy)
    assert [p for p in problems if p.file.endswith(f"{HOUSE}/{file}") and p.json_path == field], problems
    assert str(outside_png) not in opened_files


def test_validate_reports_two_escapes_in_one_house_separately(dataset_copy, editor, outside_png):
    escape_frame(editor, str(outside_png))
    escape_observer_view(editor, "../../../secret/outside.png")
    problems = validate_dataset(dataset_copy)
    fields = {p.json_path for p in problems if HOUSE in p.file}
    assert {"$[0].image_path", "$[0].rgb_path"} <= fields


def test_a_house_file_that_is_a_symlink_out_of_the_dataset_is_not_read(dataset_copy, editor, tmp_path, opened_files):
    outside = tmp_path / "secret" / "log.json"
    outside.parent.mkdir()
    log = editor.path(HOUSE, "exploration_log.json")
    shutil.copy(log, outside)
    log.unlink()
    os.symlink(outside, log)
    opened_files.clear()  # the copy above opened it; from here on nothing may
    ds = load_dataset(dataset_copy)
    assert HOUSE not in ds.houses
    assert any(p.file.endswith("exploration_log.json") and "outside the dataset" in p.message for p in ds.problems)
    assert any(p.file.endswith("exploration_log.json") and "outside the dataset" in p.message for p in validate_dataset(dataset_copy))
    assert str(outside) not in opened_files


def test_a_path_that_climbs_but_stays_inside_the_dataset_is_allowed(dataset_copy, editor):
    # The rule is "resolves inside the dataset folder", not "never contains ..". (An exploration
    # frame's image_path must also match its file's listed name, as officially: an observer view
    # has no such second rule, so it shows the confinement rule alone.)
    rgb = editor.root / "artifacts" / HOUSE / "img_from_observer"
    first = sorted(p.name for p in rgb.iterdir())[0]
    escape_observer_view(editor, f"../{HOUSE}/img_from_observer/{first}")
    ds = load_dataset(dataset_copy)
    assert HOUSE in ds.houses and not ds.problems
    assert not validate_dataset(dataset_copy)


def test_a_symlink_inside_the_dataset_to_another_file_of_it_is_allowed(dataset_copy):
    frames = dataset_copy / "artifacts" / HOUSE / "exploration_images"
    (frames / "frame_000.png").unlink()
    os.symlink("frame_001.png", frames / "frame_000.png")
    ds = load_dataset(dataset_copy)
    assert HOUSE in ds.houses and not ds.problems


def test_a_real_world_set_refuses_a_frame_symlinked_out_of_its_folder(tmp_path, outside_png, opened_files):
    from pathlib import Path

    from povagent.dataset.realworld_set import load_realworld

    demo = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"
    root = tmp_path / "rw"
    shutil.copytree(demo, root)
    frame = sorted(p for p in root.rglob("*") if p.suffix.lower() in (".png", ".jpg", ".jpeg"))[0]
    frame.unlink()
    os.symlink(outside_png, frame)
    opened_files.clear()
    with pytest.raises(DatasetError, match="outside the set's folder"):
        load_realworld(root, cache_dir=tmp_path / "cache")
    assert str(outside_png) not in opened_files

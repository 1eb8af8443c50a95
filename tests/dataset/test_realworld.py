"""The real-world set format: round trip, checks that name file and field, runnable instances."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from PIL import Image

from povagent.dataset.realworld_set import (
    INDEX_FILE,
    RealWorldInstance,
    is_realworld,
    load_realworld,
    read_realworld,
    success_breakdown,
    write_realworld,
)
from povagent.dataset.release_models import Condition, Direction
from povagent.errors import DatasetError
from povagent.geometry.letterbox import Letterbox

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


@pytest.fixture
def demo_copy(tmp_path) -> Path:
    """A writable copy of the demo set."""
    dst = tmp_path / "set"
    shutil.copytree(DEMO, dst, ignore=shutil.ignore_patterns("*.py", "*.yaml"))
    return dst


def edit_index(root: Path, change) -> None:
    data = json.loads((root / INDEX_FILE).read_text())
    change(data)
    (root / INDEX_FILE).write_text(json.dumps(data))


def test_the_demo_set_round_trips_through_write_and_read(demo_copy):
    first = read_realworld(demo_copy)
    write_realworld(first, demo_copy)
    again = read_realworld(demo_copy)
    assert again == first
    assert again.model_dump(mode="json") == first.model_dump(mode="json")


def test_a_written_file_is_byte_stable(demo_copy):
    write_realworld(read_realworld(demo_copy), demo_copy)
    once = (demo_copy / INDEX_FILE).read_bytes()
    write_realworld(read_realworld(demo_copy), demo_copy)
    assert (demo_copy / INDEX_FILE).read_bytes() == once


def test_a_folder_with_realworld_json_is_recognised(tmp_path):
    assert is_realworld(DEMO) and not is_realworld(tmp_path)


def test_condition_names_and_a_single_gt_mark_are_accepted(demo_copy):
    def change(d):
        cmd = d["houses"][0]["scenarios"][0]["commands"][0]
        cmd["condition"] = "Inferred"
        cmd["gt"] = cmd["gt"][0]

    edit_index(demo_copy, change)
    cmd = read_realworld(demo_copy).houses[0].scenarios[0].commands[0]
    assert cmd.condition is Condition.INFERRED and len(cmd.gt) == 1


def test_a_missing_image_is_named(demo_copy):
    (demo_copy / "house_1" / "frame_02.jpg").unlink()
    with pytest.raises(DatasetError, match=r"houses\[0\] \(house_1\)\.frames\[2\]: image house_1/frame_02.jpg not found"):
        read_realworld(demo_copy)


def test_an_unreadable_image_is_named(demo_copy):
    (demo_copy / "house_1" / "frame_00.jpg").write_bytes(b"junk")
    with pytest.raises(DatasetError, match=r"frame_00.jpg cannot be read"):
        read_realworld(demo_copy)


def test_a_typo_in_a_key_is_named_with_its_path(demo_copy):
    edit_index(demo_copy, lambda d: d["houses"][0]["scenarios"][0]["commands"][0].update(sentense="x"))
    with pytest.raises(DatasetError, match=r"realworld.json: houses\[0\]\.scenarios\[0\]\.commands\[0\]\.sentense: Extra inputs"):
        read_realworld(demo_copy)


def test_a_lone_surrogate_in_a_command_is_one_line_naming_the_field(demo_copy):
    edit_index(demo_copy, lambda d: d["houses"][0]["scenarios"][0]["commands"][0].update(sentence="the mug \ud800"))
    with pytest.raises(DatasetError) as err:
        read_realworld(demo_copy)
    message = str(err.value)
    assert "\n" not in message and "realworld.json: $.houses[0].scenarios[0].commands[0].sentence: text holds \\ud800" in message


def test_a_mark_with_two_shapes_is_refused(demo_copy):
    edit_index(demo_copy, lambda d: d["houses"][0]["scenarios"][0]["commands"][0]["gt"][0].update(box=[0, 0, 5, 5]))
    with pytest.raises(DatasetError, match="exactly one of point, box or region"):
        read_realworld(demo_copy)


def test_a_mark_on_a_frame_the_command_does_not_show_is_refused(demo_copy):
    edit_index(demo_copy, lambda d: d["houses"][0]["scenarios"][0]["commands"][0]["gt"][0].update(frame="house_1/nope.jpg"))
    with pytest.raises(DatasetError, match=r"commands\[0\]\.gt\[0\]\.frame: 'house_1/nope.jpg' is not one of house house_1's frames"):
        read_realworld(demo_copy)


def test_a_given_command_needs_an_observer_view(demo_copy):
    edit_index(demo_copy, lambda d: d["houses"][0]["scenarios"][0].pop("observer_view"))
    with pytest.raises(DatasetError, match="condition c needs the scenario's observer_view"):
        read_realworld(demo_copy)


def test_two_commands_for_the_same_direction_and_condition_are_refused(demo_copy):
    def change(d):
        cmds = d["houses"][0]["scenarios"][0]["commands"]
        cmds.append(dict(cmds[0]))

    edit_index(demo_copy, change)
    with pytest.raises(DatasetError, match="a second right/a command"):
        read_realworld(demo_copy)


def test_invalid_json_names_the_line(demo_copy):
    (demo_copy / INDEX_FILE).write_text('{"houses": [\n  {"id": }]}')
    with pytest.raises(DatasetError, match=r"not valid JSON.*line 2"):
        read_realworld(demo_copy)


# -- runnable instances ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def demo_dataset(tmp_path_factory):
    return load_realworld(DEMO, cache_dir=tmp_path_factory.mktemp("letterboxed"))


def test_every_command_becomes_one_instance(demo_dataset):
    ids = [i.id for i in demo_dataset.instances()]
    assert ids == [
        "house_1/kitchen/right/a", "house_1/kitchen/right/b", "house_1/kitchen/right/c",
        "house_1/bedroom/up/a", "house_1/bedroom/up/c", "house_1/study/front/a",
    ]
    assert demo_dataset.instance("house_1/bedroom/up/c").sentence == "My glasses are on top of the side table."


def test_instances_filter_like_the_release_loader(demo_dataset):
    assert len(demo_dataset.instances(conditions=["c"])) == 2
    assert len(demo_dataset.instances(directions=[Direction.UP])) == 2
    assert demo_dataset.instances(houses=["house_2"]) == []


def test_frames_are_shown_letterboxed_to_512(demo_dataset):
    inst = demo_dataset.instance("house_1/kitchen/right/a")
    assert isinstance(inst, RealWorldInstance)
    assert [f.image_path for f in inst.frames] == [f"house_1/frame_0{i}.jpg" for i in range(4)]
    for frame in inst.frames:
        with Image.open(frame.file) as im:
            assert im.size == (512, 512)
    assert inst.letterboxes[3] == Letterbox.for_size(480, 640)
    assert inst.frame_size == (512, 512)


def test_a_given_instance_shows_the_observer_view_and_its_marks_name_it(demo_dataset):
    inst = demo_dataset.instance("house_1/kitchen/right/c")
    assert [f.image_path for f in inst.frames] == ["house_1/frame_01.jpg"]
    assert [m.frame for m in inst.marks] == ["house_1/frame_01.jpg"]


def test_letterboxed_copies_are_made_once(tmp_path):
    cache = tmp_path / "cache"
    load_realworld(DEMO, cache_dir=cache)
    stamps = {p.name: p.stat().st_mtime_ns for p in cache.iterdir()}
    load_realworld(DEMO, cache_dir=cache)
    assert {p.name: p.stat().st_mtime_ns for p in cache.iterdir()} == stamps and len(stamps) == 4


def test_success_breakdown_counts_unanswered_as_failure():
    rows = [
        {"condition": "a", "direction": "right", "success": True},
        {"condition": "a", "direction": "up", "success": False},
        {"condition": "c", "direction": "up", "success": None},  # unanswered
    ]
    out = success_breakdown(rows)
    assert out["overall"] == {"n_total": 3, "n_success": 1, "success_rate": 1 / 3}
    assert out["per_condition"]["a"]["success_rate"] == 0.5
    assert out["per_direction"]["up"]["success_rate"] == 0.0

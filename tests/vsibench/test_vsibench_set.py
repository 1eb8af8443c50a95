"""A VSI-Bench set in its published shape loads into runnable instances (JSONL and Parquet
alike), each showing the frames sampled from its scene's video; a bad record or a missing video
is one problem naming file, record and field; nothing outside the set's folder is opened."""

from __future__ import annotations

import os

import pytest

from povagent.dataset.choice_sets.vsibench_set import load_vsibench
from povagent.errors import DatasetError

from .conftest import LEVEL_STEP, RECORDS, grey_level, write_jsonl, write_video


@pytest.mark.parametrize("name", ["test.jsonl", "test.parquet"])
def test_every_record_is_an_instance_showing_the_frames_asked(vsibench_folder, name):
    loaded = load_vsibench(vsibench_folder / name, frames=4, cache_dir=vsibench_folder / "cache")
    assert loaded.problems == []
    instances = loaded.instances()
    assert [i.id for i in instances] == [f"vsibench/{r['id']}" for r in RECORDS]
    assert all(len(i.frames) == 4 for i in instances)
    # scannet's 17-frame video: linspace(0, 16, 4) truncated = 0, 5, 10, 16
    scannet = loaded.instance("vsibench/6")
    assert [round(grey_level(f.file) / LEVEL_STEP) for f in scannet.frames] == [0, 5, 10, 16]


def test_the_two_formats_read_the_same_questions(vsibench_folder):
    jsonl = load_vsibench(vsibench_folder / "test.jsonl", frames=2, cache_dir=vsibench_folder / "c1").instances()
    parquet = load_vsibench(vsibench_folder / "test.parquet", frames=2, cache_dir=vsibench_folder / "c2").instances()
    assert [(i.id, i.question, i.numeric, i.answer_type) for i in jsonl] == [(i.id, i.question, i.numeric, i.answer_type) for i in parquet]


def test_choice_and_numeric_records_ask_their_own_answer_type(vsibench_folder):
    loaded = load_vsibench(vsibench_folder / "test.jsonl", frames=2, cache_dir=vsibench_folder / "cache")
    counting, distance = loaded.instance("vsibench/0"), loaded.instance("vsibench/1")
    assert (counting.answer_type, counting.numeric.gold, counting.numeric.unit) == ("number", 4.0, "")
    assert (distance.numeric.gold, distance.numeric.unit, distance.numeric.category) == (1.8, "meters", "object_abs_distance")
    direction = loaded.instance("vsibench/7")
    assert direction.answer_type == "choice" and direction.question.gold == "D"
    assert direction.question.options[3] == ("D", "back-right")


@pytest.mark.parametrize(
    ("change", "field", "says"),
    [
        ({"dataset": "../outside"}, "line 1.dataset", "a plain name"),
        ({"scene_name": "a/b"}, "line 1.scene_name", "a plain name"),
        ({"question_type": "object_colour"}, "line 1.question_type", "ten question types"),
        ({"ground_truth": "four"}, "line 1.ground_truth", "not a finite non-zero number"),
        ({"ground_truth": "0"}, "line 1.ground_truth", "divides by it"),
        ({"question": ""}, "line 1.question", "non-empty"),
        ({"id": True}, "line 1.id", "non-negative integer"),
    ],
)
def test_a_bad_record_is_one_line_naming_file_record_and_field(tmp_path, change, field, says):
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 4)
    file = write_jsonl(tmp_path / "test.jsonl", [{**RECORDS[0], **change}, RECORDS[4]])
    loaded = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache")
    assert [i.id for i in loaded.instances()] == ["vsibench/4"]
    [problem] = loaded.problems
    assert (problem.file, problem.json_path) == (str(file), field)
    assert says in problem.message and "\n" not in problem.message


def test_a_choice_record_whose_gold_is_no_option_is_refused(tmp_path):
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 4)
    file = write_jsonl(tmp_path / "test.jsonl", [{**RECORDS[4], "ground_truth": "D"}])
    [problem] = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache").problems
    assert problem.json_path == "line 1.ground_truth" and "not among the options" in problem.message


def test_a_missing_video_is_one_problem_per_record_naming_the_video(tmp_path):
    file = write_jsonl(tmp_path / "test.jsonl", RECORDS[:2])
    loaded = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache")
    assert loaded.instances() == []
    assert [(p.json_path, p.message) for p in loaded.problems] == [
        ("record 0.scene_name", "video 'arkitscenes/41069025.mp4' does not exist"),
        ("record 1.scene_name", "video 'arkitscenes/41069025.mp4' does not exist"),
    ]


def test_a_video_linked_from_outside_the_set_folder_is_never_opened(tmp_path):
    outside = write_video(tmp_path / "elsewhere" / "secret.mp4", 4)
    folder = tmp_path / "set"
    (folder / "arkitscenes").mkdir(parents=True)
    os.symlink(outside, folder / "arkitscenes" / "41069025.mp4")
    file = write_jsonl(folder / "test.jsonl", RECORDS[:1])
    [problem] = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache").problems
    assert "leads outside the dataset folder" in problem.message
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").rglob("*.png"))


def test_a_video_that_does_not_decode_is_one_problem(tmp_path):
    (tmp_path / "arkitscenes").mkdir()
    (tmp_path / "arkitscenes" / "41069025.mp4").write_bytes(b"\x00" * 64)
    file = write_jsonl(tmp_path / "test.jsonl", RECORDS[:1])
    [problem] = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache").problems
    assert problem.json_path == "record 0.scene_name" and problem.message.startswith("video 'arkitscenes/41069025.mp4': ")


def test_a_line_that_is_not_json_is_one_problem(tmp_path):
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 4)
    file = tmp_path / "test.jsonl"
    file.write_text('{"id": 0,\n' + write_jsonl(tmp_path / "x.jsonl", RECORDS[:1]).read_text(), encoding="utf-8")
    loaded = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache")
    assert [p.json_path for p in loaded.problems] == ["line 1"] and len(loaded.instances()) == 1


def test_a_parquet_file_that_is_not_parquet_is_one_problem(tmp_path):
    file = tmp_path / "test.parquet"
    file.write_bytes(b"PAR1 but not really")
    [problem] = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache").problems
    assert problem.message.startswith("not a readable Parquet file")


def test_a_missing_file_is_a_dataset_error(tmp_path):
    with pytest.raises(DatasetError, match="not found"):
        load_vsibench(tmp_path / "test.jsonl")


def test_reading_the_gold_answers_alone_opens_no_video(tmp_path):
    file = write_jsonl(tmp_path / "test.jsonl", RECORDS[:2])  # no video on disk at all
    loaded = load_vsibench(file, frames=3, cache_dir=tmp_path / "cache", decode=False)
    assert loaded.problems == [] and [i.numeric.gold for i in loaded.instances()] == [4.0, 1.8]
    assert [len(i.frames) for i in loaded.instances()] == [3, 3]
    assert not any(f.file.exists() for i in loaded.instances() for f in i.frames)


def test_reading_the_gold_answers_writes_only_each_scenes_first_frame(vsibench_folder):
    loaded = load_vsibench(vsibench_folder / "test.jsonl", frames=3, cache_dir=vsibench_folder / "cache", decode=False)
    frames = loaded.instance("vsibench/6").frames
    assert [f.file.exists() for f in frames] == [True, False, False]
    assert round(grey_level(frames[0].file) / LEVEL_STEP) == 0


def test_a_numerical_gold_written_as_a_json_number_reads_as_its_text_would(tmp_path):
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 4)
    file = write_jsonl(tmp_path / "test.jsonl", [{**RECORDS[1], "ground_truth": 1.8}, {**RECORDS[4], "ground_truth": 2}])
    loaded = load_vsibench(file, frames=2, cache_dir=tmp_path / "cache")
    assert [i.numeric.gold for i in loaded.instances()] == [1.8]
    [problem] = loaded.problems  # a letter is text: a number is no gold for a multiple-choice type
    assert problem.json_path == "line 2.ground_truth"


def test_scenes_whose_names_run_together_keep_their_own_frames(tmp_path):
    write_video(tmp_path / "a__b" / "c.mp4", 4)  # grey 0, 10, 20, 30
    write_video(tmp_path / "a" / "b__c.mp4", 16)  # its last frame is grey 150
    records = [{**RECORDS[0], "id": 0, "dataset": "a__b", "scene_name": "c"}, {**RECORDS[0], "id": 1, "dataset": "a", "scene_name": "b__c"}]
    loaded = load_vsibench(write_jsonl(tmp_path / "test.jsonl", records), frames=2, cache_dir=tmp_path / "cache")
    last = [round(grey_level(i.frames[-1].file) / LEVEL_STEP) for i in loaded.instances()]
    assert last == [3, 15]

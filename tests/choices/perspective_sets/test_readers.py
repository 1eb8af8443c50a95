"""The three readers load their sets' published formats into multiple-choice instances."""

from __future__ import annotations

import pytest

from povagent.dataset.choice_sets import load_choice_set
from povagent.dataset.evaluation_set import open_evaluation_set


def test_viewspatial_reads_every_record_with_its_gold_label_by_the_official_rule(set_file):
    loaded = load_choice_set(set_file("viewspatial"), "viewspatial")
    assert loaded.problems == []
    questions = [i.question for i in loaded.instances()]
    assert [q.gold for q in questions] == ["A", "B", "A", "C"]  # "a. towards her" reads as A
    assert questions[0].options == (("A", "right"), ("B", "left"), ("C", "front"), ("D", "back"))
    assert questions[1].category == "Person perspective - Scene Simulation Relative Direction"


def test_a_viewspatial_scene_simulation_record_shows_its_frames_in_order(set_file):
    loaded = load_choice_set(set_file("viewspatial"), "viewspatial")
    frames = loaded.instances()[1].frames
    assert [f.image_path for f in frames] == ["images/scene_2a.png", "images/scene_2b.png"]
    assert loaded.instances()[1].frame_size == (8, 6)


def test_an_external_item_has_no_direction_and_no_condition(set_file):
    instance = load_choice_set(set_file("viewspatial"), "viewspatial").instances()[0]
    assert (instance.direction, instance.condition) == (None, None)
    assert instance.id == "viewspatial/0"


def test_mindcube_reads_inline_options_the_gold_label_and_the_setting_from_the_id(set_file):
    loaded = load_choice_set(set_file("mindcube"), "mindcube")
    assert loaded.problems == []
    first, second, third = (i.question for i in loaded.instances())
    assert first.options == (("A", "Left of you"), ("B", "Behind you"), ("C", "Right of you"))
    assert [first.gold, second.gold, third.gold] == ["A", "C", "B"]
    assert [first.category, second.category, third.category] == ["among", "around", "rotation"]
    assert [len(i.frames) for i in loaded.instances()] == [2, 1, 3]


def test_3dsrbench_reads_paths_shared_indexes_and_embedded_base64_images(set_file):
    loaded = load_choice_set(set_file("3dsrbench"), "3dsrbench")
    assert loaded.problems == []
    by_id = {i.pair_id: i for i in loaded.instances()}
    assert by_id["QUES0001-1"].frames[0].file == by_id["QUES0001"].frames[0].file  # "0": record 0's image
    embedded = by_id["QUES0002"].frames[0]
    assert embedded.file.read_bytes().startswith(b"\x89PNG") and by_id["QUES0002"].frame_size == (2, 2)
    assert by_id["QUES0002-flip"].frames[0].file == embedded.file


def test_3dsrbench_names_each_copy_of_a_question_by_its_group_and_variant(set_file):
    questions = {i.pair_id: i.question for i in load_choice_set(set_file("3dsrbench"), "3dsrbench").instances()}
    assert {(q.group, q.variant) for q in questions.values()} == {
        ("QUES0001", ""), ("QUES0001", "1"), ("QUES0001", "flip"), ("QUES0001", "flip-1"), ("QUES0002", ""), ("QUES0002", "flip"),
    }  # fmt: skip
    assert questions["QUES0001"].options == (("A", "yes"), ("B", "no"))  # C "nan" and D empty are absent


@pytest.mark.parametrize("format", ["viewspatial", "mindcube", "3dsrbench"])
def test_open_evaluation_set_reads_a_set_in_the_format_named(set_file, format):
    loaded = open_evaluation_set(set_file(format), format=format)
    assert loaded.instances() and all(i.question is not None and i.question.profile == format for i in loaded.instances())


def test_a_condition_filter_selects_no_external_item(set_file):
    loaded = load_choice_set(set_file("mindcube"), "mindcube")
    assert loaded.instances(conditions=["a"]) == [] and len(loaded.instances(houses=["mindcube"])) == 3


def test_image_paths_are_read_relative_to_the_images_folder_given(set_file):
    # MindCube's official layout: data/raw/MindCube_tinybench.jsonl, images named from data/
    data = set_file("mindcube").parent
    (data / "raw").mkdir()
    moved = set_file("mindcube").rename(data / "raw" / "MindCube_tinybench.jsonl")
    assert load_choice_set(moved, "mindcube").problems  # beside the file: not there
    loaded = load_choice_set(moved, "mindcube", images=data)
    assert loaded.problems == [] and len(loaded.instances()) == 3


def test_an_item_is_found_by_its_instance_id(set_file):
    loaded = load_choice_set(set_file("3dsrbench"), "3dsrbench")
    assert loaded.instance("3dsrbench/QUES0001-flip").question.variant == "flip"
    assert loaded.instance("3dsrbench/QUES9999") is None


def test_a_set_resolves_each_image_path_once_however_many_records_name_it(tmp_path, monkeypatch):
    import json
    import os.path

    from PIL import Image

    (tmp_path / "images").mkdir()
    Image.new("RGB", (8, 6)).save(tmp_path / "images" / "a.png")
    record = {"question_type": "t", "image_path": ["images/a.png"], "question": "q?", "answer": "A. x", "choices": "A. x\nB. y"}
    bad = {**record, "image_path": ["../outside.png"]}
    (tmp_path / "set.json").write_text(json.dumps([record] * 50 + [bad] * 2))
    calls = []
    real = os.path.realpath
    monkeypatch.setattr(os.path, "realpath", lambda p, *a, **k: calls.append(p) or real(p, *a, **k))
    loaded = load_choice_set(tmp_path / "set.json", "viewspatial")
    assert len(loaded.instances()) == 50 and 0 < len(calls) < 20
    assert [p.json_path for p in loaded.problems] == ["$[50].images[0]", "$[51].images[0]"]  # each record still named
    assert len({id(i.frames[0]) for i in loaded.instances()}) == 1

"""OmniSpatial's ``data.json`` and its images read as the set publishes them, and refused record by record where bad."""

from __future__ import annotations

import json

import pytest

from povagent.dataset.choice_sets import load_choice_set, validate_choice_set

from .conftest import OMNI_RECORDS, omnispatial_records, write_omnispatial


def test_every_record_is_read_with_its_options_gold_task_and_sub_task(omnispatial_folder):
    loaded = load_choice_set(omnispatial_folder / "data.json", "omnispatial")
    assert loaded.problems == []
    read = [(i.pair_id, i.question.main_category, i.question.category, tuple(t for _, t in i.question.options), i.question.gold)
            for i in loaded.instances()]  # fmt: skip
    assert read == [(f"{task}_{rid}", task, sub, options, "ABCD"[gold]) for rid, task, sub, options, gold in OMNI_RECORDS]


def test_a_record_shows_the_image_its_task_folder_holds_for_its_question_number(omnispatial_folder):
    loaded = load_choice_set(omnispatial_folder, "omnispatial")
    images = {i.pair_id: [f.image_path for f in i.frames] for i in loaded.instances()}
    assert images["Perspective_Taking_0_0"] == images["Perspective_Taking_0_1"] == ["Perspective_Taking/0.png"]
    assert images["Dynamic_Reasoning_0_0"] == ["Dynamic_Reasoning/0.png"]
    assert loaded.instance("omnispatial/Perspective_Taking_1_0").frames[0].camera.width == 480


BROKEN = {  # case: (change to the second record, the field the one problem names)
    "answer-out-of-range": ({"answer": 4}, "$[1].answer"),
    "answer-a-bool": ({"answer": True}, "$[1].answer"),
    "answer-a-letter": ({"answer": "B"}, "$[1].answer"),
    "one-option": ({"options": ["left"]}, "$[1].options"),
    "options-not-text": ({"options": ["left", 2]}, "$[1].options"),
    "unknown-sub-task": ({"sub_task_type": "Counting"}, "$[1].sub_task_type"),
    "sub-task-of-another-task": ({"sub_task_type": "Manipulation"}, "$[1].sub_task_type"),
    "no-question": ({"question": ""}, "$[1].question"),
    "id-not-text": ({"id": 7}, "$[1].id"),
    "id-with-slash": ({"id": "0/1"}, "$[1].id"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_a_bad_record_is_one_problem_naming_file_and_field_and_the_rest_is_read(tmp_path, case):
    records = omnispatial_records()[:4]
    change, field = BROKEN[case]
    records[1] = {**records[1], **change}
    path = write_omnispatial(tmp_path / "set", records)
    loaded = load_choice_set(path, "omnispatial")
    assert [(p.file, p.json_path) for p in loaded.problems] == [(str(path), field)]
    assert len(loaded.instances()) == 3


def test_a_missing_image_is_one_problem_naming_the_record_and_image(tmp_path):
    path = write_omnispatial(tmp_path / "set", omnispatial_records()[:4])
    (tmp_path / "set" / "Perspective_Taking" / "1.png").unlink()
    loaded = load_choice_set(path, "omnispatial")
    assert [(p.json_path, p.message) for p in loaded.problems] == [
        ("record Perspective_Taking_1_0.images[0]", "image 'Perspective_Taking/1.png' does not exist")
    ]


def test_an_image_outside_the_set_s_folder_is_never_opened(tmp_path):
    (tmp_path / "Egocentric").mkdir()
    records = [{**omnispatial_records()[0]}]
    path = write_omnispatial(tmp_path / "set", records)
    data = json.loads(path.read_text())
    data[0]["task_type"] = "../Perspective_Taking"  # not a task type: refused before any path is made
    path.write_text(json.dumps(data))
    loaded = load_choice_set(path, "omnispatial")
    assert [p.json_path for p in loaded.problems] == ["$[0].sub_task_type"] and loaded.instances() == []


def test_a_repeated_task_and_id_is_a_problem_and_the_first_record_is_kept(tmp_path):
    records = omnispatial_records()[:3]
    records[2] = {**records[2], "id": "0_0"}
    loaded = load_choice_set(write_omnispatial(tmp_path / "set", records), "omnispatial")
    message = "'Perspective_Taking_0_0' (task type and id) is used by an earlier record; this one left out"
    assert [(p.json_path, p.message) for p in loaded.problems] == [("$[2].id", message)] and len(loaded.instances()) == 2


@pytest.mark.parametrize(("text", "message"), [
    ("{not json", "not valid JSON"), ('{"id": "0_0"}', "must hold a JSON list"), ("[" * 100_000, "nest"),
])  # fmt: skip
def test_a_file_that_is_not_the_set_s_list_is_one_problem(tmp_path, text, message):
    path = tmp_path / "data.json"
    path.write_text(text)
    (problem,) = validate_choice_set(path, "omnispatial")
    assert problem.file == str(path) and message in problem.message and "\n" not in problem.message


def test_validate_decodes_every_image(omnispatial_folder):
    assert validate_choice_set(omnispatial_folder / "data.json", "omnispatial") == []

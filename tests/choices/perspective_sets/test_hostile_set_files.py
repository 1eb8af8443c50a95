"""A hostile set file costs the readers time linear in its size and gets one line per bad record:
a lone surrogate and a nesting 100,000 deep are refused by the release reader's own rules."""

from __future__ import annotations

import json
import time

import pytest

from povagent.dataset.choice_sets import load_choice_set, validate_choice_set
from povagent.dataset.choice_sets.mindcube_records import inline_options

#: a quadratic scan of a megabyte takes hours: the bound ends the test instead
pytestmark = pytest.mark.timeout(60)

DEEP = "[" * 100_000 + "]" * 100_000
#: The release reader's one line for it (povagent.dataset.json_files.TOO_DEEP).
TOO_DEEP = "nests lists or objects too deeply to be a release file"


def _viewspatial_with(set_file, record_text: str):
    """The fixture set with ``record_text`` (raw JSON) as one more record, first."""
    path = set_file("viewspatial")
    path.write_text("[" + record_text + "," + path.read_text().lstrip()[1:])
    return path


def _mindcube_with(set_file, line: str):
    """The fixture set with ``line`` as its first line."""
    path = set_file("mindcube")
    path.write_text(line + "\n" + path.read_text())
    return path


VIEWSPATIAL_RECORD = {"question_type": "Camera perspective - Relative Direction", "image_path": ["images/scene_1.png"],
                      "question": "Where is the lamp?", "answer": "A. right", "choices": "A. right\nB. left"}  # fmt: skip
MINDCUBE_RECORD = {"id": "among_0009_q1", "question": "<image>Where is the plant? A. Left B. Right",
                   "images": ["images/room_2.png"], "gt_answer": "A"}  # fmt: skip


def test_a_lone_surrogate_in_a_viewspatial_question_leaves_the_record_out_with_one_line(set_file):
    text = json.dumps(VIEWSPATIAL_RECORD).replace("Where is", "Where\\ud800 is")
    loaded = load_choice_set(_viewspatial_with(set_file, text), "viewspatial")
    assert [(p.json_path, "lone surrogate" in p.message) for p in loaded.problems] == [("$[0].question", True)]
    assert len(loaded.instances()) == 4  # the fixture's own four, none holding the surrogate
    assert all("\ud800" not in i.sentence for i in loaded.instances())


def test_a_lone_surrogate_escaped_in_capitals_in_a_viewspatial_key_is_refused_too(set_file):
    text = json.dumps(VIEWSPATIAL_RECORD)[:-1] + ', "note\\uDBFF": "x"}'
    loaded = load_choice_set(_viewspatial_with(set_file, text), "viewspatial")
    assert len(loaded.problems) == 1 and loaded.problems[0].json_path.startswith("$[0].note") and "lone surrogate" in loaded.problems[0].message


def test_a_viewspatial_question_escaping_a_surrogate_pair_is_text_and_kept(set_file):
    text = json.dumps(VIEWSPATIAL_RECORD).replace("Where is", "Where \\ud83d\\ude00 is")
    loaded = load_choice_set(_viewspatial_with(set_file, text), "viewspatial")
    assert loaded.problems == [] and len(loaded.instances()) == 5
    assert any("\U0001f600" in i.sentence for i in loaded.instances())


def test_a_lone_surrogate_in_a_mindcube_question_leaves_the_record_out_with_one_line(set_file):
    line = json.dumps(MINDCUBE_RECORD).replace("Where is", "Where\\udfff is")
    problems = validate_choice_set(_mindcube_with(set_file, line), "mindcube")
    assert [(p.json_path, "lone surrogate" in p.message) for p in problems] == [("line 1.question", True)]


def test_a_lone_surrogate_in_a_key_of_a_record_is_refused_too(set_file):
    line = json.dumps(MINDCUBE_RECORD)[:-1] + ', "meta\\ud800": 1}'
    problems = validate_choice_set(_mindcube_with(set_file, line), "mindcube")
    assert len(problems) == 1 and problems[0].json_path.startswith("line 1.meta") and "lone surrogate" in problems[0].message


def test_a_3dsrbench_cell_cannot_hold_a_surrogate_its_utf8_bytes_are_refused(set_file):
    # UTF-8 has no encoding of a surrogate; bytes that would be one (CESU-8) are not UTF-8
    path = set_file("3dsrbench")
    lines = path.read_bytes().split(b"\n")
    lines[1] = lines[1].replace(b"Is the man", b"Is the \xed\xa0\x80man")
    path.write_bytes(b"\n".join(lines))
    problems = validate_choice_set(path, "3dsrbench")
    assert problems[0].json_path == "line 2" and "not UTF-8" in problems[0].message  # (line 3 shared its image)
    assert all("\ud800" not in i.sentence for i in load_choice_set(path, "3dsrbench").instances())


def test_a_viewspatial_file_nested_100000_deep_is_one_line_not_a_recursion_error(set_file):
    path = set_file("viewspatial")
    path.write_text(DEEP)
    problems = validate_choice_set(path, "viewspatial")
    assert [p.message for p in problems] == [TOO_DEEP]


def test_a_viewspatial_record_nested_near_the_parsers_limit_is_named_not_reencoded(set_file):
    # parsed whole, yet deep enough that encoding it again inside the reader overflows the stack
    depth = 900
    loaded = load_choice_set(_viewspatial_with(set_file, "[" * depth + "]" * depth), "viewspatial")
    assert [(p.json_path, p.message) for p in loaded.problems] == [("$[0]", "a record must be a JSON object (got list)")]


def test_a_mindcube_line_nested_100000_deep_is_one_line_and_the_rest_is_read(set_file):
    loaded = load_choice_set(_mindcube_with(set_file, DEEP), "mindcube")
    assert [(p.json_path, p.message) for p in loaded.problems] == [("line 1", TOO_DEEP)]
    assert len(loaded.instances()) == 3


def test_the_inline_option_scan_takes_linear_time_on_a_megabyte_of_labels():
    question = "A. x B. y " + "A. " * 350_000  # every A a run start with no B after: the old scan was quadratic (hours)
    start = time.process_time()
    options = inline_options(question)
    assert time.process_time() - start < 2.0
    assert options[0] == ("A", "x") and options[1][0] == "B" and len(options) == 2


def test_the_inline_option_scan_takes_the_last_a_with_a_b_after_it():
    assert inline_options("A. one B. two A. three B. four C. five A. six") == (("A", "three"), ("B", "four"), ("C", "five A. six"))
    assert inline_options("A. one C. two B. three D. four") == (("A", "one C. two"), ("B", "three D. four"))
    assert inline_options("A. lonely") == ()


def test_a_megabyte_mindcube_question_is_validated_in_linear_time(set_file):
    record = dict(MINDCUBE_RECORD, question="<image>Where? A. Left B. Right " + "A. " * 350_000)
    path = _mindcube_with(set_file, json.dumps(record))
    start = time.process_time()
    problems = validate_choice_set(path, "mindcube")
    assert time.process_time() - start < 3.0
    assert problems == []


def test_a_run_over_a_set_with_a_lone_surrogate_and_its_resume_score_the_other_records(choice_pipeline, set_file):
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    _viewspatial_with(set_file, json.dumps(VIEWSPATIAL_RECORD).replace("Where is", "Where\\ud800 is"))
    first = run_pipeline(load_pipeline(choice_pipeline("viewspatial")))
    again = run_pipeline(load_pipeline(choice_pipeline("viewspatial")))  # the resume: it crashed every time
    assert (first.n_total, first.exit_code, again.n_pending, again.exit_code) == (4, 0, 0, 0)


def test_a_viewspatial_record_listing_a_megabyte_of_options_is_one_short_line(set_file):
    record = dict(VIEWSPATIAL_RECORD, choices="A. right\n" * 100_000)
    loaded = load_choice_set(_viewspatial_with(set_file, json.dumps(record)), "viewspatial")
    (problem,) = loaded.problems
    assert problem.json_path == "$[0].choices" and "at most 26 options" in problem.message and len(str(problem)) < 300

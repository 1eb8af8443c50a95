"""Reading lmms-eval's ``--log_samples`` JSONL: the fields as the pinned writer leaves them, and a
log treated as untrusted (one line per bad record, bounded lines, only the named file)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from povagent.errors import PredictionsError
from povagent.results import harness_logs
from povagent.results.harness_logs import gold_label, options_in_prompt
from povagent.results.lmms_eval_log import read_lmms_eval_log

PROMPT = "Question: Where is the lamp?\nChoices: A. right\nB. left\nC. front\nD. back\nReply only to the corresponding option.\nAnswer:"


def record(doc_id: int = 0, **fields) -> dict:
    """One line as lmms-eval's save_results_samples writes it for the viewspatial task."""
    out = {"doc_id": doc_id, "target": "B. left", "filtered_resps": "B", "token_counts": [None], "doc_hash": "ab" * 32,
           "overall_accuracy": {"score": 1.0},
           "camera_perspective_relative_direction_accuracy": {"score": 1.0, "question_type": "Camera perspective - Relative Direction",
                                                              "target_type": "Camera perspective - Relative Direction"},
           "input": PROMPT}  # fmt: skip
    out.update(fields)
    return out


def write(tmp_path: Path, *records: object) -> Path:
    path = tmp_path / "20261207_samples_viewspatial.jsonl"
    path.write_text("".join((r if isinstance(r, str) else json.dumps(r)) + "\n" for r in records), encoding="utf-8")
    return path


def test_a_record_gives_its_reply_gold_options_and_category(tmp_path):
    [reply] = read_lmms_eval_log(write(tmp_path, record(7))).replies
    assert (reply.item, reply.where, reply.reply, reply.gold) == ("7", "line 1", "B", "B")
    assert reply.options == (("A", "right"), ("B", "left"), ("C", "front"), ("D", "back"))
    assert reply.category == "Camera perspective - Relative Direction"


def test_without_resps_the_reply_is_filtered_resps_which_lmms_eval_logged_equal(tmp_path):
    log = read_lmms_eval_log(write(tmp_path, record(filtered_resps="C")))
    assert (log.replies[0].reply, log.replies[0].filtered, log.stripped) == ("C", "C", 0)


def test_resps_is_the_reply_as_written_and_filtered_resps_what_lmms_eval_stripped(tmp_path):
    log = read_lmms_eval_log(write(tmp_path, record(resps="<think>A?</think>\nB", filtered_resps="B")))
    assert (log.replies[0].reply, log.replies[0].filtered, log.stripped) == ("<think>A?</think>\nB", "B", 1)


def test_a_list_of_repeats_is_read_by_its_first_reply(tmp_path):
    log = read_lmms_eval_log(write(tmp_path, record(resps=[["D", "A"]], filtered_resps=["D", "A"])))
    assert log.replies[0].reply == "D"


def test_the_category_and_question_id_come_from_the_tasks_metric_dicts(tmp_path):
    metric = {"index": 3, "qid": "VIN6MS3J-flip-1", "score": 0.0, "category": "orientation_viewpoint", "main_category": "orientation"}
    [reply] = read_lmms_eval_log(write(tmp_path, {"doc_id": 3, "target": "A", "filtered_resps": "A", "vanilla_accuracy": metric})).replies
    assert (reply.category, reply.main_category, reply.question_id) == ("orientation_viewpoint", "orientation", "VIN6MS3J-flip-1")


def test_omni_spatials_sub_task_counts_in_its_task_type(tmp_path):
    metric = {"score": 1.0, "task_type": "Perspective_Taking", "sub_task_type": "Allocentric"}
    [reply] = read_lmms_eval_log(write(tmp_path, {"doc_id": 0, "target": "A", "filtered_resps": "A", "omni_spatial_score": metric})).replies
    assert (reply.category, reply.main_category) == ("Allocentric", "Perspective_Taking")


def test_a_logged_doc_of_an_older_lmms_eval_gives_the_gold_and_options(tmp_path):
    doc = {"question": "q", "A": "left", "B": "right", "C": "nan", "answer": "B", "category": "height_higher"}
    [reply] = read_lmms_eval_log(write(tmp_path, {"doc_id": 0, "doc": doc, "target": "", "filtered_resps": "B"})).replies
    assert (reply.gold, reply.options, reply.category) == ("B", (("A", "left"), ("B", "right")), "height_higher")


def test_mindcubes_grounded_output_target_names_the_label_after_its_answer_tag():
    assert gold_label("<think>I see a chair. A is wrong.</think><answer>C. Behind the sofa</answer>") == "C"
    assert gold_label("B. left") == gold_label("(B)") == gold_label("B") == "B"


def test_options_are_the_longest_run_of_labelled_lines_in_order():
    assert options_in_prompt("Options:\nA. yes\nB. no\nPlease select.") == (("A", "yes"), ("B", "no"))
    assert options_in_prompt("A. one\nC. two") == (("A", "one"),)
    assert options_in_prompt("no options here") == ()


def test_without_listed_options_the_labels_run_from_a_to_the_gold_one(tmp_path):
    [reply] = read_lmms_eval_log(write(tmp_path, record(input="Which? A. x B. y C. z D. w E. v", target="<answer>E. v</answer>"))).replies
    assert [label for label, _ in reply.options] == ["A", "B", "C", "D", "E"]


@pytest.mark.parametrize(
    ("bad", "where", "message"),
    [
        ("[1, 2]", "line 2", "a record must be a JSON object (got list); record left out"),
        ('{"doc_id": 0, "target": "B"', "line 2", "not a JSON record (Expecting ',' delimiter); record left out"),
        (
            {"doc_id": True, "target": "B", "filtered_resps": "B"},
            "line 2.doc_id",
            "required, a number or text of at most 200 characters naming the document; record left out",
        ),
        ({"doc_id": 5, "target": "B"}, "line 2.filtered_resps", "required, the reply as text of at most 1000000 characters; record left out"),
        (
            {"doc_id": 5, "target": "B", "filtered_resps": "B", "resps": {"x": 1}},
            "line 2.resps",
            "the reply must be text of at most 1000000 characters; record left out",
        ),
        (
            {"doc_id": 5, "target": "none of them", "filtered_resps": "B"},
            "line 2.target",
            "'none of them' names no option label A-Z (nor a number, with no options in the prompt); record left out",
        ),
        ({"doc_id": 0, "target": "B", "filtered_resps": "B"}, "line 2.doc_id", "'0' is logged by an earlier line; this one left out"),
    ],
)
def test_a_bad_record_is_one_problem_naming_file_line_and_field_and_the_rest_are_read(tmp_path, bad, where, message):
    path = write(tmp_path, record(0), bad, record(1))
    log = read_lmms_eval_log(path)
    assert [r.item for r in log.replies] == ["0", "1"]
    assert [str(p) for p in log.problems] == [f"{path}: {where}: {message}"]


def test_a_lone_surrogate_is_a_bad_record_named_by_its_field_not_a_crash_later(tmp_path):
    path = write(tmp_path, '{"doc_id": 0, "target": "B", "filtered_resps": "B\\ud800"}', record(1))
    log = read_lmms_eval_log(path)
    assert [r.item for r in log.replies] == ["1"]
    assert str(log.problems[0]).startswith(f"{path}: line 1.filtered_resps: text holds \\ud800 at character 1, a lone surrogate")
    assert str(log.problems[0]).endswith("; record left out")


def test_a_reply_longer_than_a_parser_reads_is_a_bad_record(tmp_path):
    log = read_lmms_eval_log(write(tmp_path, record(filtered_resps="B" * (harness_logs.MAX_REPLY_CHARS + 1))))
    assert log.replies == [] and log.problems[0].json_path == "line 1.filtered_resps"


def test_an_over_long_line_ends_the_reading_with_one_problem(tmp_path, monkeypatch):
    import povagent.results.lmms_eval_log as module

    monkeypatch.setattr(module, "MAX_LOG_LINE_BYTES", 2000)
    path = write(tmp_path, record(0), record(1, input="x" * 5000), record(2))
    log = read_lmms_eval_log(path)
    assert [r.item for r in log.replies] == ["0"]
    assert [str(p) for p in log.problems] == [f"{path}: line 2: longer than 2000 bytes; this line and the rest of the file are not read"]


def test_a_line_that_is_not_utf8_is_named(tmp_path):
    path = write(tmp_path, record(0))
    path.write_bytes(path.read_bytes() + b'{"doc_id": 1, "target": "\xff"}\n')
    log = read_lmms_eval_log(path)
    assert [str(p) for p in log.problems] == [f"{path}: line 2: byte 26 is not UTF-8; record left out"]


def test_only_a_regular_file_is_read(tmp_path):
    with pytest.raises(PredictionsError, match="is a folder, not a regular file"):
        read_lmms_eval_log(tmp_path)
    fifo = tmp_path / "pipe.jsonl"
    os.mkfifo(fifo)
    with pytest.raises(PredictionsError, match="not a regular file"):
        read_lmms_eval_log(fifo)  # refused at once, never waited on


def test_a_file_over_the_size_bound_is_refused_without_reading_it(tmp_path, monkeypatch):
    import povagent.results.lmms_eval_log as module

    monkeypatch.setattr(module, "MAX_LOG_BYTES", 100)
    with pytest.raises(PredictionsError, match="cannot be read"):
        read_lmms_eval_log(write(tmp_path, record(0), record(1)))


def test_options_written_inline_after_options_are_read_from_their_line(tmp_path):
    # lmms-eval's mmsi_bench prompt: the question with MMSI-Bench's own "Options: A: ..., B: ...", then the post-prompt
    prompt = "Where is the lamp?\nOptions: A: Front left, B: Back, right side, C: Above\nAnswer with the option's letter. Enclose it within ``."
    [reply] = read_lmms_eval_log(write(tmp_path, record(target="C", input=prompt))).replies
    assert reply.options == (("A", "Front left"), ("B", "Back, right side"), ("C", "Above"))


def test_omnispatial_tests_sub_task_and_task_are_the_category_and_its_main_category(tmp_path):
    metric = {
        "id": "3_1",
        "query": "...",
        "gt_content": "B",
        "pred": "Answer: B",
        "task": "Perspective_Taking",
        "sub_task": "omnispatial_egocentric",
        "is_correct": True,
    }
    [reply] = read_lmms_eval_log(write(tmp_path, {"doc_id": 0, "target": "B", "filtered_resps": "Answer: B", "omnispatial": metric, "input": PROMPT})).replies
    assert (reply.category, reply.main_category) == ("omnispatial_egocentric", "Perspective_Taking")


def test_a_number_target_with_no_options_in_the_prompt_is_a_numerical_question(tmp_path):
    doc = {"question_type": "object_counting", "ground_truth": "4", "prediction": "3", "MRA:.5:.95:.05": 0.5}
    prompt = "These are frames of a video.\nHow many chairs are in this room?\nPlease answer the question using a single word or phrase."
    [reply] = read_lmms_eval_log(write(tmp_path, {"doc_id": 2, "target": "4", "filtered_resps": "3", "vsibench_overall": doc, "input": prompt})).replies
    assert (reply.gold, reply.gold_number, reply.options, reply.category) == ("4", 4.0, (), "object_counting")


def test_a_number_target_beside_listed_options_is_no_numerical_question(tmp_path):
    log = read_lmms_eval_log(write(tmp_path, record(target="3")))
    assert log.replies == [] and log.problems[0].json_path == "line 1.target"

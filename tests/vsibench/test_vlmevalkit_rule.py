"""VLMEvalKit's VSI-Bench rule (``vlmevalkit-vsibench`` parser, ``vsibench-vlmevalkit`` scorer) gives
what VLMEvalKit gives on the same replies.

The expected values were computed by RUNNING, from copies fetched outside the repository,
open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94's ``compute_mcq_score`` and
``compute_na_score`` (``vlmeval/dataset/utils/spatial_bench/cal_scores.py``, calling
``can_match_option`` and ``can_match_na`` of ``matching_func.py``) on each reply as
``VsiBench.evaluate`` hands it to them: dumped in a prediction file (``dump_tsv``), loaded by pandas
(``load``), ``str()``'d. A differential check of 200,000 random replies built from the rule's
tokens (tags, digits, signs, number words, brackets, Unicode digits) against ``can_match_na``
found no difference.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path

import pytest

from povagent.answers.numeric_question import NumericQuestion, number_answer_schema
from povagent.answers.spec import AnswerSpec, choice_answer_schema
from povagent.dataset.choice_sets.external import image_camera
from povagent.dataset.choice_sets.vsibench_records import scene_question
from povagent.dataset.choice_sets.vsibench_set import scene_instance
from povagent.dataset.instances import Frame
from povagent_plugins.parsers.vsibench.vlmevalkit import MAX_LIST_CHARS, VlmevalkitVSIBenchParser, vlmevalkit_number
from povagent_plugins.scorers.vsibench_vlmevalkit import VlmevalkitVSIBenchScorer, vlmevalkit_relative_error

OPTIONS = ["A. left", "B. right", "C. back", "D. front"]
INF = math.inf

#: (gold, reply, the letter compute_mcq_score extracted (None: its False), its hit)
CHOICE = [
    ("B", "B", "B", 1.0), ("B", "b", "B", 1.0), ("B", "N/A", None, 0.0), ("A", "N/A", None, 0.0), ("A", "n/a", None, 0.0),
    ("A", "#N/A", None, 0.0), ("C", "<answer>C</answer>", "C", 1.0), ("C", "B or C", None, 0.0), ("C", "The answer is C.", "C", 1.0),
    ("C", "Option C", "C", 1.0), ("D", "d) sofa", "D", 1.0), ("A", "I think A is wrong, the final answer is B", "B", 0.0),
    ("B", "", None, 0.0), ("B", "none", None, 0.0), ("B", "None", None, 0.0), ("B", "sofa", None, 0.0), ("A", "**A**", "A", 1.0),
    ("D", "<think>A?</think>D", "D", 1.0), ("B", "[B]", "B", 1.0), ("C", "C\u200b", "C", 1.0),
]  # fmt: skip
#: (gold, reply, the number compute_na_score extracted (None: none), its MRA:.5:.95:.05)
NUMBER = [
    ("3", "3", 3.0, 1.0), ("3", "three", 3.0, 1.0), ("21", "twenty-one", -1.0, 0.0), ("1200", "1,200", 200.0, 0.0),
    ("3.5", "between 3 and 4 meters", 4.0, 0.8), ("2.5", "[2.5, 7]", 2.5, 1.0), ("2.5", "[2.5 meters]", None, 0.0), ("2.5", "[]", None, 0.0),
    ("4.5", "<answer>4.5 m</answer> or 7", 4.5, 1.0), ("4.5", "<ANSWER>4.5</answer>", 4.5, 1.0), ("4.5", "<answer>4.5<b></answer> 7", 7.0, 0.0),
    ("5", "<think>maybe 9</think>5 chairs", 5.0, 1.0), ("5", "<think>5</think>no idea", 5.0, 1.0), ("5", "I count 5, not 6", 6.0, 0.6),
    ("2", "-2", -2.0, 0.0), ("2", "+2", 2.0, 1.0), ("3.5", "3-4 m", -4.0, 0.0), ("120", "1.2e2", 120.0, 1.0), ("0.5", ".5", 0.5, 1.0),
    ("7", "\u200b7", 7.0, 1.0), ("7", "seven\u200b", 7.0, 1.0), ("7", "N/A", None, 0.0), ("7", "", None, 0.0), ("7", "-1.#IND", None, 0.0),
    ("7", "Seventeen", 17.0, 0.0), ("12", "TWELVE", 12.0, 1.0), ("4", "\u0664", 4.0, 1.0), ("30", "1e999", INF, 0.0), ("0", "0", 0.0, 1.0),
    ("0", "0.5", 0.5, 0.1), ("-2", "-3", -3.0, 0.1), ("10", "x\u00b2", None, 0.0), ("3.5", "3.5m\u00b2", 3.5, 1.0),
    ("8", "About 8.4 meters.", 8.4, 1.0), ("8", "8 (estimated)", 8.0, 1.0),
]  # fmt: skip


def instance(question_type: str, gold: str):
    """A VSI-Bench question; a gold of 0 or below (which the set's file never holds, and its reader
    refuses) as a prediction file may give it."""
    numerical = question_type != "route_planning"
    record = {"id": 0, "dataset": "scannet", "scene_name": "scene0000_00", "question_type": question_type, "question": "?",
              "options": None if numerical else OPTIONS, "ground_truth": "1" if numerical else gold}  # fmt: skip
    item = scene_question(record, "line 1")
    assert not isinstance(item, tuple), item
    made = scene_instance(item, (Frame(0, "f", Path("f.png"), image_camera(4, 4)),))
    return replace(made, numeric=NumericQuestion("?", float(gold), category=question_type)) if numerical else made


def spec_of(question) -> AnswerSpec:
    if question.question is None:
        return AnswerSpec(schema=number_answer_schema(), asks_frame=False)
    return AnswerSpec(schema=choice_answer_schema(question.question.labels), asks_frame=False, choices=question.question.options)


def scored(question_type: str, gold: str, reply: str):
    """(the parse, the score as rescore-log counts it: a reply read as nothing is 0)."""
    question = instance(question_type, gold)
    parse = VlmevalkitVSIBenchParser().parse(reply, spec_of(question))
    fields = VlmevalkitVSIBenchScorer().score(question, parse) if parse.answered else None
    return parse, VlmevalkitVSIBenchScorer.metrics[0].unscored if fields is None else fields["score"]


@pytest.mark.parametrize(("gold", "reply", "letter", "hit"), CHOICE)
def test_a_choice_reply_reads_the_letter_and_hit_vlmevalkit_gives(gold, reply, letter, hit):
    parse, score = scored("route_planning", gold, reply)
    assert (parse.choice if parse.answered else None, score) == (letter, hit)


@pytest.mark.parametrize(("gold", "reply", "number", "mra"), NUMBER)
def test_a_numerical_reply_reads_the_number_and_mra_vlmevalkit_gives(gold, reply, number, mra):
    parse, score = scored("object_counting", gold, reply)
    assert (parse.number if parse.answered else None) == number
    assert score == pytest.approx(mra, abs=1e-12)


def test_a_missing_cell_as_pandas_reads_it_names_no_letter_though_the_letter_rule_alone_reads_one():
    from povagent_plugins.parsers.mcq.vlmevalkit_spatial import spatial_bench_label

    assert spatial_bench_label("N/A") == "A"  # can_match_option("N/A") on its own
    assert not VlmevalkitVSIBenchParser().parse("N/A", AnswerSpec(schema={}, asks_frame=False, choices=(("A", "x"), ("B", "y")))).answered


def test_vlmevalkits_relative_error_divides_by_the_golds_size_and_takes_a_gold_of_zero():
    assert vlmevalkit_relative_error(-3.0, -2.0) == 0.5  # the set's code: (-3 - -2) / -2 = -0.5, met at every threshold
    assert vlmevalkit_relative_error(0.5, 0.0) == 0.5  # the set's code divides by zero
    assert vlmevalkit_relative_error(2.2, 2.0) == pytest.approx(0.1)


def test_the_last_number_is_read_where_lmms_eval_reads_the_first_and_the_set_the_first_word():
    assert vlmevalkit_number("between 2 and 3 meters") == 3.0
    assert vlmevalkit_number("It is 4 m, not 6 m.") == 6.0
    assert vlmevalkit_number("<think>12?</think>\n\n9 chairs") == 9.0  # after the reasoning first
    assert vlmevalkit_number("<think>12?</think>\n\nno idea") == 12.0  # else anywhere


def test_a_list_literal_python_cannot_read_reads_no_number_as_upstream():
    assert vlmevalkit_number("[" * 30_000 + "]" * 30_000) is None  # too deeply nested: can_match_na's except
    assert vlmevalkit_number("[2 meters]") is None
    assert vlmevalkit_number("[__import__('os').system('touch ran')]") is None  # a literal only: nothing is run


def test_a_list_literal_longer_than_the_bound_reads_no_number():
    assert vlmevalkit_number("[" + "1, " * 10 + "1]") == 1.0
    assert vlmevalkit_number("[" + "1, " * (MAX_LIST_CHARS // 3) + "1]") is None


N = 200_000
HOSTILE = {
    "answer-tags-never-closed": "<answer" * (N // 7),
    "answer-tags-one-bracket-at-the-end": "<answer" * (N // 7) + ">1",
    "a-long-number-in-an-answer-tag": "<answer>" + "1" * N + " x",
    "many-answer-blocks-with-numbers": "<answer> 3 x" * (N // 12),
    "digits-and-dots": "1." * (N // 2),
    "think-tags-spaced": "< think" + " " * N,
    "number-words": "one two " * (N // 8),
    "deep-list-within-the-bound": "[" * 30_000 + "]" * 30_000,
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_hostile_reply_is_read_in_linear_time(case):
    spec = AnswerSpec(schema=number_answer_schema(), asks_frame=False)
    start = time.process_time()  # this process's CPU time: immune to a loaded machine
    VlmevalkitVSIBenchParser().parse(HOSTILE[case], spec)
    # upstream's TAGGED_NUMERIC_ANSWER is quadratic on the first: 3.5 s here, a minute and a half at a megabyte
    assert time.process_time() - start < 1.0

"""VSI-Bench's rules give what the upstream functions give on the same replies.

The expected values below were computed by running the upstream functions themselves, from
copies fetched outside the repository, on this corpus: ``vsibench_process_results`` and
``vsibench_aggregate_results`` of ``lmms_eval/tasks/vsibench/utils.py`` at
vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8 (the set's own), and
``vsibench_process_results``, ``_compute_all_subscores`` and ``vsibench_aggregate_overall`` at
EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3 after that commit's
``strip_reasoning_tags`` with its default ``--reasoning_tags`` (what its evaluator does first).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.answers.numeric_question import number_answer_schema
from povagent.answers.spec import AnswerSpec, choice_answer_schema
from povagent.dataset.choice_sets.external import image_camera
from povagent.dataset.choice_sets.vsibench_records import scene_question
from povagent.dataset.choice_sets.vsibench_set import load_vsibench, scene_instance
from povagent.dataset.instances import Frame
from povagent.scoring.metrics import metric_value
from povagent_plugins.parsers.vsibench.first_word import VSIBenchParser, first_word
from povagent_plugins.parsers.vsibench.lmms import VSIBenchLmmsParser, extract_number
from povagent_plugins.scorers.vsibench_scorer import VSIBenchScorer, lmms_overall, official_overall, per_type_scores

from .conftest import RECORDS

OPTIONS = {"A": "A. left", "B": "B. right", "C": "C. back", "D": "D. front"}

#: (question type, ground truth, reply, official score, lmms-eval score), the scores as the
#: upstream functions gave them.
CORPUS = [
    ("object_rel_direction_easy", "A", "A", 1.0, 1.0),
    ("object_rel_direction_easy", "B", "b.", 1.0, 1.0),
    ("object_rel_direction_easy", "C", "The answer is C.", 0.0, 0.0),
    ("object_rel_direction_medium", "A", "A. left", 1.0, 1.0),
    ("object_rel_direction_medium", "D", " D", 0.0, 1.0),  # the first word is empty; lmms-eval strips first
    ("object_rel_direction_hard", "B", "B.\n", 0.0, 1.0),  # "B.\n": the dot is not trailing
    ("object_rel_direction_hard", "C", "<think>C</think>C", 0.0, 1.0),
    ("object_rel_distance", "A", "A", 1.0, 1.0),
    ("object_rel_distance", "B", "A", 0.0, 0.0),
    ("route_planning", "C", "c", 1.0, 1.0),
    ("obj_appearance_order", "D", "D...", 1.0, 1.0),
    ("obj_appearance_order", "A", "", 0.0, 0.0),
    ("object_counting", "3", "3", 1.0, 1.0),
    ("object_counting", "4", "three", 0.0, 0.6),
    ("object_counting", "5", "There are 5 chairs.", 0.0, 1.0),
    ("object_counting", "2", "2.", 1.0, 1.0),
    ("object_abs_distance", "2.5", "2.2 meters", 0.8, 0.8),
    ("object_abs_distance", "1.8", "about 1.5", 0.0, 0.7),
    ("object_abs_distance", "3.0", "1,000", 0.0, 0.0),
    ("object_size_estimation", "120", "1e2", 0.7, 0.0),  # float("1e2") = 100; extract_number reads "1"
    ("object_size_estimation", "45", "nan", 0.0, 0.0),
    ("object_size_estimation", "60", "twenty-one", 0.0, 0.0),
    ("room_size_estimation", "20.5", "20", 1.0, 1.0),
    ("room_size_estimation", "14", "<think>maybe 12</think>15 square meters", 0.0, 0.9),
    ("room_size_estimation", "30", "inf", 0.0, 0.0),
]
#: vsibench_aggregate_results @ 51e089c3 on the official scores (its percentages).
OFFICIAL_TABLE = {
    "overall": 46.52777777777778, "object_counting": 50.0, "object_abs_distance": 26.666666666666668,
    "object_size_estimation": 23.333333333333332, "room_size_estimation": 33.33333333333333, "object_rel_distance": 50.0,
    "object_rel_direction": 38.888888888888886, "route_planning": 100.0, "obj_appearance_order": 50.0,
}  # fmt: skip
#: _compute_all_subscores @ 75571cfe on lmms-eval's scores (fractions), and its rounded overall.
LMMS_TABLE = {
    "overall": 0.6152777777777778, "obj_appearance_order": 0.5, "object_abs_distance": 0.5, "object_counting": 0.9,
    "object_rel_distance": 0.5, "object_size_estimation": 0.0, "room_size_estimation": 0.6333333333333333,
    "route_planning": 1.0, "object_rel_direction": 0.8888888888888888,
}  # fmt: skip
LMMS_OVERALL = 0.615278


def corpus_instance(index: int, question_type: str, gold: str):
    record = {"id": index, "dataset": "scannet", "scene_name": "scene0000_00", "question_type": question_type,
              "question": "?", "options": list(OPTIONS.values()), "ground_truth": gold}  # fmt: skip
    item = scene_question(record, f"line {index + 1}")
    assert not isinstance(item, tuple), item
    return scene_instance(item, (Frame(0, "f", Path("f.png"), image_camera(4, 4)),))


def spec_of(instance) -> AnswerSpec:
    if instance.question is None:
        return AnswerSpec(schema=number_answer_schema(), asks_frame=False)
    return AnswerSpec(schema=choice_answer_schema(instance.question.labels), asks_frame=False, choices=instance.question.options)


def scores(parser) -> list[tuple[str, float]]:
    """(question type, score) per corpus reply, as the runner scores it: a reply read as
    nothing is not scored and counts 0 (the score metric's ``unscored``)."""
    out = []
    for index, (question_type, gold, reply, _, _) in enumerate(CORPUS):
        instance = corpus_instance(index, question_type, gold)
        parse = parser.parse(reply, spec_of(instance))
        fields = VSIBenchScorer().score(instance, parse) if parse.answered else None
        score = VSIBenchScorer.metrics[0].unscored if fields is None else fields["score"]
        out.append((question_type, score))
    return out


def test_each_reply_scores_what_the_sets_own_code_gives_it():
    assert [s for _, s in scores(VSIBenchParser())] == pytest.approx([row[3] for row in CORPUS], abs=1e-12)


def test_each_reply_scores_what_lmms_eval_gives_it():
    assert [s for _, s in scores(VSIBenchLmmsParser())] == pytest.approx([row[4] for row in CORPUS], abs=1e-12)


def test_the_official_overall_is_the_mean_of_the_per_type_scores_with_directions_merged():
    table = official_overall(per_type_scores(scores(VSIBenchParser())))
    assert {k: 100 * v for k, v in table.items()} == pytest.approx(OFFICIAL_TABLE, abs=1e-9)


def test_the_official_overall_by_hand():
    # directions: easy 2/3, medium 1/2, hard 0/2 -> 7/18; then the 8 types' mean
    per_type = [1 / 2, 4 / 15, 7 / 30, 1 / 3, 1 / 2, 7 / 18, 1.0, 1 / 2]
    assert official_overall(per_type_scores(scores(VSIBenchParser())))["overall"] == pytest.approx(sum(per_type) / 8, abs=1e-12)


def test_lmms_evals_overall_reads_numbers_anywhere_and_rounds_to_six_places():
    table = lmms_overall(per_type_scores(scores(VSIBenchLmmsParser())))
    assert table["overall"] == LMMS_OVERALL
    assert {k: v for k, v in table.items() if k != "overall"} == pytest.approx({k: v for k, v in LMMS_TABLE.items() if k != "overall"}, abs=1e-6)


def test_lmms_eval_needs_all_three_direction_levels_where_the_set_merges_only_when_easy_is_there():
    per_type = {"object_counting": 1.0, "object_rel_direction_medium": 0.5}
    assert official_overall(per_type) == {"overall": 0.75, "object_counting": 1.0, "object_rel_direction_medium": 0.5}
    with pytest.raises(ValueError, match="KeyError"):
        lmms_overall(per_type)


def test_an_unknown_question_type_is_refused_as_upstream_refuses_it():
    with pytest.raises(ValueError, match="Unknown question type: object_colour"):
        per_type_scores([("object_colour", 1.0)])


@pytest.mark.parametrize(
    ("reply", "word"),
    [("A", "A"), ("A. left", "A"), ("b.", "b"), (" A", ""), ("A.\n", "A."), ("A\nB", "A\nB"), ("D...", "D"), ("", "")],
)
def test_the_first_word_is_before_the_first_space_with_trailing_dots_removed(reply, word):
    assert first_word(reply) == word


@pytest.mark.parametrize(
    ("reply", "number"),
    [("3", 3.0), ("There are 3 boxes", 3.0), ("three", 3.0), ("Twenty-one", 21.0), ("three hundred and twenty-one", 321.0),
     ("one apple, room 2", 1.0), ("-2.5 m", -2.5), ("1,000", 1.0), ("two thousand", 2000.0), ("none", None), ("", None)],
)  # fmt: skip
def test_lmms_evals_extract_number_takes_the_first_number_or_number_words(reply, number):
    assert extract_number(reply) == number


def test_oracle_replies_score_one_hundred_percent_under_both_readings(vsibench_folder):
    loaded = load_vsibench(vsibench_folder / "test.parquet", frames=2, cache_dir=vsibench_folder / "cache")
    gold = {str(r["id"]): r["ground_truth"] for r in RECORDS}
    for parser in (VSIBenchParser(), VSIBenchLmmsParser()):
        rows = []
        for instance in loaded.instances():
            parse = parser.parse(gold[instance.pair_id], spec_of(instance))
            fields = VSIBenchScorer().score(instance, parse)
            rows.append((fields["category"], fields["score"]))
        assert all(score == 1.0 for _, score in rows)
        assert official_overall(per_type_scores(rows))["overall"] == 1.0
        assert lmms_overall(per_type_scores(rows))["overall"] == 1.0


def test_a_numeric_row_carries_mra_and_both_errors():
    instance = corpus_instance(0, "object_abs_distance", "2.5")
    fields = VSIBenchScorer().score(instance, VSIBenchParser().parse("2.2", spec_of(instance)))
    assert fields["mra"] == pytest.approx(0.8) and fields["abs_error"] == pytest.approx(0.3) and fields["rel_error"] == pytest.approx(0.12)
    assert (fields["gold"], fields["unit"], fields["category"]) == (2.5, "meters", "object_abs_distance")


def test_a_choice_reply_naming_no_option_is_kept_as_the_word_and_never_the_gold():
    instance = corpus_instance(0, "route_planning", "A")
    parse = VSIBenchParser().parse("Answer: A", spec_of(instance))
    assert parse.choice == "Answer:"
    assert VSIBenchScorer().score(instance, parse)["correct"] is False


def test_a_question_asking_neither_an_option_nor_a_number_is_not_read():
    from povagent.answers.spec import point_answer_schema

    for parser in (VSIBenchParser(), VSIBenchLmmsParser()):
        parse = parser.parse("3", AnswerSpec(schema=point_answer_schema(8, 8)))
        assert not parse.answered and "neither" in parse.reason


def zero_gold_instance():
    """A counting question whose gold is 0 (a prediction file may hold one; the set's own file never does)."""
    from dataclasses import replace

    from povagent.answers.numeric_question import NumericQuestion

    return replace(corpus_instance(0, "object_counting", "1"), numeric=NumericQuestion("?", 0.0, category="object_counting"))


def test_a_numerical_row_whose_gold_is_0_is_unscorable_says_why_and_carries_no_score():
    instance = zero_gold_instance()
    fields = VSIBenchScorer().score(instance, VSIBenchParser().parse("2", spec_of(instance)))
    assert fields["unscorable"] is True and "gold is 0" in fields["unscorable_reason"]
    assert "score" not in fields and "mra" not in fields and "rel_error" not in fields  # left out of the figures, not scored 0
    assert (fields["number"], fields["abs_error"]) == (2.0, 2.0)
    unscorable = next(m for m in VSIBenchScorer.metrics if m.name == "unscorable")
    assert metric_value(unscorable, fields, answered=True) == 1.0  # counted by the declared metric
    assert metric_value(VSIBenchScorer.metrics[0], fields, answered=True) is None


def test_a_reply_reading_no_number_scores_0_even_where_the_gold_is_0_as_upstream_reaches_its_worst_case_first():
    instance = zero_gold_instance()
    fields = VSIBenchScorer().score(instance, VSIBenchParser().parse("none", spec_of(instance)))
    assert fields["score"] == 0.0 and "unscorable" not in fields

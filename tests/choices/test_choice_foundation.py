"""The choice answer type end to end: strategy -> baseline -> parser -> score step -> scorer."""

from __future__ import annotations

import asyncio

import pytest

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.spec import AnswerSpec, ParseStatus
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, TextPart
from povagent.plugins import get_plugin_host
from povagent.run.score_step import AnswerScoring
from povagent_plugins.answers.choice_answer import CHOICE
from povagent_plugins.backends.baselines import OracleBaseline, RandomBaseline
from povagent_plugins.parsers.choice_parser import ChoiceParser
from povagent_plugins.scorers.choice_scorer import ChoiceScorer
from povagent_plugins.strategies.choice import ChoiceStrategy

OPTIONS = (("A", "left"), ("B", "right"), ("C", "front"), ("D", "behind"))
SPEC = AnswerSpec(schema={}, choices=OPTIONS)


@pytest.mark.parametrize(
    ("text", "label"),
    [
        ("C", "C"),
        ("(B)", "B"),
        ("A.", "A"),
        ("D) behind", "D"),
        ("Answer: B", "B"),
        ("**Final answer:** C", "C"),
        ("The answer is A.", "A"),
        ('{"choice": "B"}', "B"),
        ('I think so. {"answer": "D. behind"}', "D"),
        ("<think>It could be A or B.</think>\nC", "C"),
        ("the reasoning ends here</think>B", "B"),
        ("Looking at the images...\n\nfront", "C"),
    ],
)
def test_the_choice_parser_reads_a_label(text, label):
    parse = ChoiceParser().parse(text, SPEC)
    assert parse.answered and parse.choice == label


@pytest.mark.parametrize("text", ["", "   ", "Because the chair is there.", "E", "b", "I cannot tell from these images.", "A or B"])
def test_the_choice_parser_reads_no_label_where_there_is_none(text):
    parse = ChoiceParser().parse(text, SPEC)
    assert parse.status is ParseStatus.UNPARSEABLE and parse.choice is None and not parse.answered


def test_an_option_text_is_a_repaired_reading():
    parse = ChoiceParser().parse("Right.", SPEC)
    assert parse.status is ParseStatus.REPAIRED and parse.choice == "B"


def test_a_question_refuses_a_gold_label_that_is_no_option():
    with pytest.raises(ValueError, match="gold label 'E'"):
        ChoiceQuestion("where?", OPTIONS, gold="E")


def test_the_strategy_shows_the_images_then_the_question_and_its_options(choice_instance, tmp_path):
    request = ChoiceStrategy().build(choice_instance, ImageStore())
    parts = request.messages[0].parts
    assert [type(p) for p in parts] == [ImagePart] * len(choice_instance.frames) + [TextPart]
    text = parts[-1].text
    assert text.startswith(choice_instance.question.question + "\nA. left\nB. right\nC. front\nD. behind\n")
    assert request.answer.choices == OPTIONS and not request.answer.asks_frame


def _score(instance, text):
    scoring = AnswerScoring(parser=ChoiceParser(), scorers={"choice": ChoiceScorer()}, dataset=None, answer_type=CHOICE)
    return scoring.score_answer(instance, ChoiceStrategy().answer_spec(instance), text)


def test_the_oracle_answers_the_gold_label_and_scores_correct(choice_instance, tmp_path):
    request = ChoiceStrategy().build(choice_instance, ImageStore())
    response = asyncio.run(OracleBaseline().complete(request, ImageStore()))
    scored = _score(choice_instance, response.text)
    assert scored.scores["choice"] == {"answered": True, "correct": True, "chosen": "C", "gold": "C", "category": "relation"}
    assert scored.prediction.answer_type == "choice" and scored.prediction.value == {"choice": "C"}


def test_a_wrong_label_scores_incorrect_and_a_non_answer_is_a_parse_error(choice_instance):
    assert _score(choice_instance, "A").scores["choice"]["correct"] is False
    scored = _score(choice_instance, "no idea")
    assert scored.status == "parse_error" and scored.scores == {}


def test_random_answers_are_seeded_labels_spread_over_the_options(choice_instance, tmp_path):
    import dataclasses

    store = ImageStore()
    request = ChoiceStrategy().build(choice_instance, store)
    seen = []
    for pair in range(40):
        inst = dataclasses.replace(choice_instance, pair_id=str(pair))
        req = dataclasses.replace(request, instance=inst)
        seen.append(asyncio.run(RandomBaseline(seed=3).complete(req, store)).text)
    again = asyncio.run(RandomBaseline(seed=3).complete(dataclasses.replace(request, instance=dataclasses.replace(choice_instance, pair_id="0")), store))
    assert set(seen) == {"A", "B", "C", "D"} and again.text == seen[0]


def test_a_choice_pipeline_naming_no_parser_gets_the_choice_parser_and_a_point_parser_is_refused():
    from povagent.config.plugin_checks import parser_misfit, strategy_default_parser

    host = get_plugin_host()
    assert strategy_default_parser(host, "choice") == "choice"
    assert parser_misfit(host, "choice", "choice") is None
    assert "reads point answers" in (parser_misfit(host, "choice", "official") or "")


def test_a_question_sharing_a_kept_option_list_still_refuses_a_gold_label_that_is_no_option():
    kept = ChoiceQuestion("where?", (("A", "up"), ("B", "down")), gold="A")  # the list is kept with its labels
    with pytest.raises(ValueError, match=r"gold label 'C' is not among the options \(A, B\)"):
        ChoiceQuestion("and now?", (("A", "up"), ("B", "down")), gold="C")
    assert ChoiceQuestion("and now?", (("A", "up"), ("B", "down")), gold="B").options is kept.options


def test_a_question_with_a_kept_option_list_whose_labels_repeat_is_refused_each_time():
    for _ in range(2):  # the second one meets the kept list
        with pytest.raises(ValueError, match="option labels repeat: A, A"):
            ChoiceQuestion("where?", (("A", "up"), ("A", "down")), gold="A")

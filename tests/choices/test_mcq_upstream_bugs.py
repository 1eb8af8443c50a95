"""The known upstream bugs: each reproduced under its rule's name, and the corrected reading beside
it differs from it exactly on the probe replies where the bug fires (tagged in mcq_corpus.yaml by
instrumenting the upstream function)."""

from __future__ import annotations

import dataclasses

import pytest

from povagent.answers.choice_question import ChoiceQuestion
from povagent.plugins import get_plugin_host

from .mcq_corpus import read_with, replies, reply_ids

each_reply = pytest.mark.parametrize("reply", replies(), ids=reply_ids())
EIGHT_OPTIONS = tuple((label, f"option {label}") for label in "ABCDEFGH")


def asking(instance, gold: str, options=EIGHT_OPTIONS):
    """``instance`` asking a question whose gold label is ``gold``."""
    return dataclasses.replace(instance, question=ChoiceQuestion(question="Where?", options=options, gold=gold))


def scored(scorer: str, parser: str, reply: str, instance) -> bool:
    """Whether ``scorer`` counts ``reply``, read by ``parser``, as a hit on ``instance``."""
    return get_plugin_host(()).scorer(scorer, {}).score(instance, read_with(parser, reply))["correct"]


@each_reply
def test_the_corrected_shared_reader_differs_exactly_where_the_phrase_bug_fires(reply):
    upstream = read_with("lmms-mcq-extract", reply["answer"]).choice
    corrected = read_with("lmms-mcq-extract-corrected", reply["answer"]).choice
    assert (corrected != upstream) == ("lmms-mcq-extract-phrase" in reply["bugs"])


def test_the_shared_reader_reads_the_answer_is_c_because_as_b_and_the_correction_as_c():
    reply = "The answer is C. Because the sofa faces the window, the lamp is in front."
    assert read_with("lmms-mcq-extract", reply).choice == "B"
    assert read_with("lmms-mcq-extract-corrected", reply).choice == "C"


@each_reply
@pytest.mark.parametrize("gold", ["B", "G"])
def test_choice_vlmevalkit_counts_hits_as_compute_mcq_score_does(reply, gold, choice_instance):
    instance = asking(choice_instance, gold)
    assert scored("choice-vlmevalkit", "vlmevalkit-spatial", reply["answer"], instance) == bool(reply["compute_mcq_score_hit"][gold])


@each_reply
@pytest.mark.parametrize("gold", ["B", "G"])
def test_the_corrected_vlmevalkit_hit_differs_exactly_where_neither_side_reads_a_letter(reply, gold, choice_instance):
    instance = asking(choice_instance, gold)
    upstream = scored("choice-vlmevalkit", "vlmevalkit-spatial", reply["answer"], instance)
    corrected = scored("choice-vlmevalkit-corrected", "vlmevalkit-spatial", reply["answer"], instance)
    # the rule never reads G: the bug fires on a gold G wherever the reply reads no letter either
    fires = gold == "G" and reply["labels"]["vlmevalkit-spatial"] is None
    assert (upstream != corrected) == fires
    assert not corrected or upstream


def test_a_refusal_is_a_vlmevalkit_hit_on_a_gold_the_rule_cannot_read(choice_instance):
    instance = asking(choice_instance, "G")
    assert scored("choice-vlmevalkit", "vlmevalkit-spatial", "I cannot determine the answer.", instance)
    assert not scored("choice-vlmevalkit-corrected", "vlmevalkit-spatial", "I cannot determine the answer.", instance)


@each_reply
@pytest.mark.parametrize("gold", ["A", "B"])
def test_choice_sparbench_counts_hits_as_sparbench_exact_match_does(reply, gold, choice_instance):
    instance = asking(choice_instance, gold, choice_instance.question.options)
    assert scored("choice-sparbench", "sparbench-lmms", reply["answer"], instance) == bool(reply["sparbench_exact_match_hit"][gold])


@each_reply
@pytest.mark.parametrize("gold", ["A", "B"])
def test_the_corrected_sparbench_reading_differs_exactly_where_its_bugs_fire(reply, gold, choice_instance):
    instance = asking(choice_instance, gold, choice_instance.question.options)
    upstream = scored("choice-sparbench", "sparbench-lmms", reply["answer"], instance)
    corrected = scored("choice", "sparbench-lmms-corrected", reply["answer"], instance)
    fires = "sparbench-empty" in reply["bugs"] or ("sparbench-first-character" in reply["bugs"] and upstream)
    assert (upstream != corrected) == fires


def test_an_empty_reply_is_a_sparbench_hit_and_no_answer_corrected(choice_instance):
    instance = asking(choice_instance, "D", choice_instance.question.options)
    assert scored("choice-sparbench", "sparbench-lmms", "", instance)
    assert not scored("choice", "sparbench-lmms-corrected", "", instance)

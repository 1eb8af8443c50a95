"""Each upstream-rule parser gives, on every probe reply, the label its upstream rule gives at the
pinned commit (the labels in mcq_corpus.yaml were produced by running the upstream functions)."""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, ParseStatus
from povagent.plugins import get_plugin_host

from .mcq_corpus import read_with, replies, reply_ids

each_reply = pytest.mark.parametrize("reply", replies(), ids=reply_ids())


def agrees(parser: str, reply: dict) -> None:
    """The parser's label is the upstream label, and a parse without one is a typed non-response."""
    parsed = read_with(parser, reply["answer"])
    assert parsed.choice == reply["labels"][parser], (parser, reply["answer"])
    assert (parsed.status == ParseStatus.OK) == (parsed.choice is not None)
    assert parsed.choice is not None or parsed.reason


@each_reply
def test_viewspatial_reads_every_reply_as_lmms_eval_viewspatial_does(reply):
    agrees("viewspatial", reply)


@each_reply
def test_mindcube_reads_every_reply_as_the_mindcube_cascade_does(reply):
    agrees("mindcube", reply)


@each_reply
def test_3dsrbench_lmms_reads_every_reply_as_lmms_eval_3dsrbench_does(reply):
    agrees("3dsrbench-lmms", reply)


@each_reply
def test_vlmevalkit_exact_reads_every_reply_as_can_infer_does(reply):
    agrees("vlmevalkit-exact", reply)


@each_reply
def test_vlmevalkit_spatial_reads_every_reply_as_can_match_option_does(reply):
    agrees("vlmevalkit-spatial", reply)


@each_reply
def test_lmms_mcq_extract_reads_every_reply_as_the_shared_reader_does(reply):
    agrees("lmms-mcq-extract", reply)


def test_the_corpus_probes_every_form_the_rules_disagree_on():
    ids = reply_ids()
    assert len(ids) >= 60 and len(set(ids)) == len(ids)
    # the rules do not all agree: a corpus on which they did could not tell one from another
    disagreeing = [r for r in replies() if len({label for label in r["labels"].values()}) > 1]
    assert len(disagreeing) >= 20


def test_vlmevalkit_exact_says_z_where_vlmevalkit_reads_no_option():
    parsed = read_with("vlmevalkit-exact", "Cannot determine the answer")
    assert parsed.choice is None and parsed.status == ParseStatus.UNPARSEABLE and "Z" in parsed.reason


def test_a_rule_parser_reads_nothing_without_options():
    parsed = get_plugin_host(()).parser("viewspatial", {}).parse("B", AnswerSpec(schema={}))
    assert parsed.choice is None and parsed.status == ParseStatus.UNPARSEABLE


def test_vlmevalkit_exact_refuses_options_not_labelled_by_capital_letters():
    spec = AnswerSpec(schema={}, asks_frame=False, choices=(("1", "left"), ("2", "right")))
    parsed = get_plugin_host(()).parser("vlmevalkit-exact", {}).parse("left", spec)
    assert parsed.choice is None and "capital letters" in parsed.reason

"""MMSI-Bench's and OmniSpatial's rule parsers read every probe reply as the upstream code does.

The corpora (``mmsi_corpus.yaml``, ``omnispatial_corpus.yaml``) hold, per reply, the label and
the hit (gold A, gold B) each upstream function gave when run at the commit its header names.
A parser's label must be that label; the ``choice`` scorer's verdict on the parse must be that
hit, so a score read with the parser is the harness's own.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.spec import AnswerSpec, ParseStatus
from povagent.plugins import get_plugin_host
from povagent_plugins.scorers.choice_scorer import ChoiceScorer

from .mcq_corpus import FAST_LOADER

HERE = Path(__file__).parent
OPTIONS = (("A", "left"), ("B", "right"), ("C", "front"), ("D", "back"))
SPEC = AnswerSpec(schema={"type": "object", "properties": {"choice": {"enum": ["A", "B", "C", "D"]}}}, asks_frame=False, choices=OPTIONS)
MMSI_RULES = ("mmsi-official", "mmsi-lmms")
OMNISPATIAL_RULES = ("omnispatial-re", "omnispatial-json", "omnispatial-direct", "omnispatial-lmms-direct", "omnispatial-lmms-re")


@cache
def _corpus(name: str) -> list[dict[str, Any]]:
    return yaml.load((HERE / name).read_text(encoding="utf-8"), Loader=FAST_LOADER)["replies"]


def _cases(name: str, rules: tuple[str, ...]) -> list[Any]:
    return [pytest.param(rule, reply, id=f"{rule}-{reply['id']}") for reply in _corpus(name) for rule in rules]


def _read(parser: str, reply: str):
    return get_plugin_host(()).parser(parser, {}).parse(reply, SPEC)


class _Instance:
    """What the choice scorer reads of an instance: its question."""

    def __init__(self, gold: str) -> None:
        self.id = "probe"
        self.question = ChoiceQuestion("Where is it?", OPTIONS, gold)


def _hit(parsed, gold: str) -> int:
    return int(ChoiceScorer().score(_Instance(gold), parsed)["correct"])  # type: ignore[arg-type]


@pytest.mark.parametrize(("rule", "reply"), _cases("mmsi_corpus.yaml", MMSI_RULES))
def test_mmsi_rules_read_every_reply_as_upstream_does(rule, reply):
    assert _read(rule, reply["reply"]).choice == reply["labels"][rule]


@pytest.mark.parametrize(("rule", "reply"), _cases("mmsi_corpus.yaml", MMSI_RULES))
def test_mmsi_rules_score_every_reply_as_upstream_does(rule, reply):
    parsed = _read(rule, reply["reply"])
    assert {gold: _hit(parsed, gold) for gold in "AB"} == {gold: reply["hits"][gold][rule] for gold in "AB"}


@pytest.mark.parametrize(("rule", "reply"), _cases("omnispatial_corpus.yaml", OMNISPATIAL_RULES))
def test_omnispatial_rules_read_every_reply_as_upstream_does(rule, reply):
    assert _read(rule, reply["reply"]).choice == reply["labels"][rule]


@pytest.mark.parametrize(("rule", "reply"), _cases("omnispatial_corpus.yaml", OMNISPATIAL_RULES))
def test_omnispatial_rules_score_every_reply_as_upstream_does(rule, reply):
    parsed = _read(rule, reply["reply"])
    assert {gold: _hit(parsed, gold) for gold in "AB"} == {gold: reply["hits"][gold][rule] for gold in "AB"}


@pytest.mark.parametrize("reply", _corpus("omnispatial_corpus.yaml"), ids=lambda r: r["id"])
def test_omnispatial_re_marks_its_read_a_fallback_as_a_repair(reply):
    parsed = _read("omnispatial-re", reply["reply"])
    assert (parsed.status is ParseStatus.REPAIRED) == reply["re_found_no_answer_line"]


@pytest.mark.parametrize("reply", _corpus("omnispatial_corpus.yaml"), ids=lambda r: r["id"])
def test_omnispatial_re_corrected_reads_no_answer_where_the_set_s_rule_falls_back_to_a(reply):
    parsed = _read("omnispatial-re-corrected", reply["reply"])
    expected = None if reply["re_found_no_answer_line"] else reply["labels"]["omnispatial-re"]
    assert parsed.choice == expected


def test_the_corpora_probe_what_the_rules_disagree_on():
    mmsi = _corpus("mmsi_corpus.yaml")
    omni = _corpus("omnispatial_corpus.yaml")
    assert any(r["labels"]["mmsi-official"] != r["labels"]["mmsi-lmms"] for r in mmsi)
    assert any(r["re_found_no_answer_line"] and r["hits"]["A"]["omnispatial-re"] for r in omni)  # the read-A bug fires
    for a in OMNISPATIAL_RULES:
        assert any(len({r["labels"][a], r["labels"][b]}) == 2 for r in omni for b in OMNISPATIAL_RULES if b != a)


def test_a_long_hostile_reply_is_read_in_linear_time():
    import time

    hostile = "answer " * 20_000 + " " * 100_000 + "<answer>" * 20_000
    started = time.process_time()
    for rule in (*MMSI_RULES, *OMNISPATIAL_RULES, "omnispatial-re-corrected"):
        _read(rule, hostile)
    assert time.process_time() - started < 2.0

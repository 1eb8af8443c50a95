"""The rules a set's logged replies are scored by come from the registry: the set's official rule,
then each registered parser that names the set among its harness's (``harness_sets``)."""

from __future__ import annotations

import re

import pytest

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.errors import PluginError
from povagent.scoring.log_rules import known_sets, set_rules
from povagent_plugins.parsers.mcq.rule import RuleParser

COMMIT = re.compile(r"^[\w.-]+/[\w.-]+@[0-9a-f]{40}$")


def test_each_choice_set_has_its_official_rule_first_then_the_harness_rules(povagent_host):
    got = {s: [(r.parser, r.scorer, r.harness, r.official) for r in set_rules(povagent_host, s)] for s in ("viewspatial", "mindcube", "3dsrbench")}
    assert got == {
        "viewspatial": [("viewspatial-official", "choice", "ViewSpatial-Bench", True), ("viewspatial", "choice", "lmms-eval", False),
                        ("vlmevalkit-spatial", "choice-vlmevalkit", "VLMEvalKit", False)],
        "mindcube": [("mindcube-official", "choice-mindcube", "MindCube", True), ("mindcube", "choice", "lmms-eval", False),
                     ("vlmevalkit-spatial", "choice-vlmevalkit", "VLMEvalKit", False)],
        "3dsrbench": [("vlmevalkit-exact", "choice-3dsrbench", "VLMEvalKit", True), ("3dsrbench-lmms", "choice-3dsrbench", "lmms-eval", False)],
    }  # fmt: skip


def test_every_rule_names_the_commit_it_follows(povagent_host):
    for name in known_sets(povagent_host):
        for rule in set_rules(povagent_host, name):
            assert COMMIT.match(rule.source), (name, rule)


def test_the_lmms_eval_rules_say_they_strip_reasoning_as_lmms_eval_does(povagent_host):
    filters = {r.parser: r.harness_filter for r in set_rules(povagent_host, "viewspatial")}
    assert filters == {"viewspatial-official": "", "viewspatial": "lmms-eval's reasoning-tag strip", "vlmevalkit-spatial": ""}


class _FirstLetter(RuleParser):
    """A third party's harness rule: the reply's first character."""

    source = "example/harness@" + "0" * 40
    harness = "example-harness"
    harness_sets = (("viewspatial", "choice"),)

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        return text[:1] or None


class _Plugin:
    @hookimpl
    def register_parsers(self, register) -> None:
        register("first-letter", _FirstLetter, description="the first character")


def test_a_harness_rule_plugs_in_by_naming_its_set_with_no_edit_of_the_command(povagent_host):
    povagent_host.add_plugin(_Plugin(), name="first-letter-plugin")
    try:
        rules = set_rules(povagent_host, "viewspatial")
        assert ("first-letter", "choice", "example-harness", "example/harness@" + "0" * 40) in [(r.parser, r.scorer, r.harness, r.source) for r in rules]
        assert rules[0].parser == "viewspatial-official"  # the official rule stays first
        assert "first-letter" not in [r.parser for r in set_rules(povagent_host, "mindcube")]
    finally:
        povagent_host.remove_plugin("first-letter-plugin")


def test_an_unknown_set_is_refused_naming_the_sets_a_log_can_be_scored_as(povagent_host):
    with pytest.raises(PluginError, match=r"unknown set 'vsi': a log can be scored as .*viewspatial"):
        set_rules(povagent_host, "vsi")

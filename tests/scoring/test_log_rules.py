"""The rules a set's logged replies are scored by come from the registry: the set's official rule,
then each registered parser that names the set among its harness's (``harness_sets``)."""

from __future__ import annotations

import re

import pytest

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.errors import PluginError
from povagent.scoring.log_rules import official_rules, set_rules
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.vlmevalkit_load import LOAD_FILTER

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
    for name in official_rules(povagent_host):
        for rule in set_rules(povagent_host, name):
            assert COMMIT.match(rule.source), (name, rule)


def test_the_lmms_eval_rules_say_they_strip_reasoning_as_lmms_eval_does(povagent_host):
    filters = {r.parser: r.harness_filter for r in set_rules(povagent_host, "viewspatial")}
    assert filters == {"viewspatial-official": "", "viewspatial": "lmms-eval's reasoning-tag strip", "vlmevalkit-spatial": LOAD_FILTER}


@pytest.mark.parametrize("set_name", ["viewspatial", "mindcube", "3dsrbench", "mmsi", "omnispatial", "vsibench"])
def test_every_vlmevalkit_rule_says_it_reads_replies_through_vlmevalkits_load_and_no_other_rule_does(povagent_host, set_name):
    rules = set_rules(povagent_host, set_name)
    assert any(r.harness == "VLMEvalKit" for r in rules)
    assert all((r.harness_filter == LOAD_FILTER) == (r.harness == "VLMEvalKit") for r in rules), rules


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


class _FourthSet:
    """A set added later: its format (official rule: the first-letter parser) and an lmms-eval rule for it."""

    @hookimpl
    def register_dataset_formats(self, register) -> None:
        from povagent.dataset.formats import DatasetFormat, DocsRow

        def never_read(request):
            raise AssertionError("rescore-log never reads a set")

        register("fourthset", DatasetFormat(
            key="fourthset", description="a fourth choice set", read=never_read, record_id=lambda i: f"record {i}", answer_type="choice",
            official_parser="first-letter", official_scorer="choice", source="example/fourthset@" + "1" * 40, licence="CC-BY-4.0",
            docs_row=DocsRow("FourthSet", "here", "the file", "how-to/perspective-sets.md"),
        ), description="a fourth choice set")  # fmt: skip

    @hookimpl
    def register_parsers(self, register) -> None:
        class Lmms(_FirstLetter):
            source, harness, harness_sets = "EvolvingLMMs-Lab/lmms-eval@" + "2" * 40, "lmms-eval", (("fourthset", "choice"),)

        register("first-letter", _FirstLetter, description="the first character")
        register("fourthset-lmms", Lmms, description="lmms-eval's reading of the fourth set")


def test_a_set_added_later_plugs_in_by_registering_its_format_and_naming_its_rules(povagent_host, tmp_path):
    import json

    from povagent.run.rescore_log import rescore_log

    povagent_host.add_plugin(_FourthSet(), name="fourth-set")
    try:
        rules = set_rules(povagent_host, "fourthset")
        assert [(r.parser, r.official, r.source) for r in rules] == [
            ("first-letter", True, "example/harness@" + "0" * 40), ("fourthset-lmms", False, "EvolvingLMMs-Lab/lmms-eval@" + "2" * 40),
        ]
        log = tmp_path / "samples_fourthset.jsonl"
        log.write_text("".join(json.dumps({"doc_id": k, "target": "B", "filtered_resps": reply, "input": "A. x\nB. y"}) + "\n"
                               for k, reply in enumerate(["B", "A", "Bee"])), encoding="utf-8")  # fmt: skip
        result = rescore_log(log, "lmms-eval", "fourthset", host=povagent_host, n_boot=0)
        assert [(r.rule, r.overall) for r in result.rules] == [("first-letter", 2 / 3), ("fourthset-lmms", 2 / 3)]
    finally:
        povagent_host.remove_plugin("fourth-set")


def test_a_set_whose_answers_are_no_choice_is_not_offered(povagent_host):
    assert "povbench" not in official_rules(povagent_host)
    assert {"viewspatial", "mindcube", "3dsrbench"} <= set(official_rules(povagent_host))


def test_an_unknown_set_is_refused_naming_the_sets_a_log_can_be_scored_as(povagent_host):
    with pytest.raises(PluginError, match=r"unknown set 'vsi': a log can be scored as .*viewspatial"):
        set_rules(povagent_host, "vsi")


def test_mmsi_omnispatial_and_vsibench_have_their_own_rule_first_then_the_harnesses(povagent_host):
    got = {s: [(r.parser, r.scorer, r.harness, r.official) for r in set_rules(povagent_host, s)] for s in ("mmsi", "omnispatial", "vsibench")}
    assert got == {
        "mmsi": [("mmsi-official", "choice", "MMSI-Bench", True), ("mmsi-lmms", "choice", "lmms-eval", False),
                 ("vlmevalkit-spatial", "choice-vlmevalkit", "VLMEvalKit", False)],
        "omnispatial": [("omnispatial-re", "choice", "OmniSpatial", True), ("omnispatial-lmms-direct", "choice", "lmms-eval", False),
                        ("omnispatial-lmms-re", "choice", "lmms-eval", False), ("omnispatial-re-corrected", "choice", "OmniSpatial, corrected", False),
                        ("vlmevalkit-spatial", "choice-vlmevalkit", "VLMEvalKit", False)],
        "vsibench": [("vsibench", "vsibench", "VSI-Bench", True), ("vlmevalkit-vsibench", "vsibench-vlmevalkit", "VLMEvalKit", False),
                     ("vsibench-lmms", "vsibench", "lmms-eval", False)],
    }  # fmt: skip

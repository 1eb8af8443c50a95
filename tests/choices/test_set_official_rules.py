"""The sets' own rules (``viewspatial-official``, ``mindcube-official``) and the harness readings
beside them give, on every probe reply, the label the upstream code gives at the pinned commits
(set_rules_probes.yaml was produced by running it; the probe corpus's ``official_code`` labels too)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.answers.spec import ParseStatus

from .mcq_corpus import FAST_LOADER, read_with, replies

PROBES = Path(__file__).with_name("set_rules_probes.yaml")
RULES = ("viewspatial-official", "mindcube-official", "viewspatial", "mindcube", "3dsrbench-lmms", "vlmevalkit-exact")


@cache
def probes() -> list[dict]:
    return yaml.load(PROBES.read_text(encoding="utf-8"), Loader=FAST_LOADER)["replies"]


def test_the_probes_answer_the_corpus_s_options():
    options = yaml.safe_load(PROBES.read_text(encoding="utf-8"))["options"]
    assert options == [["A", "right"], ["B", "left"], ["C", "front"], ["D", "back"]]


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("probe", probes(), ids=[p["id"] for p in probes()])
def test_each_rule_reads_each_probe_as_its_upstream_code_does(rule, probe):
    parsed = read_with(rule, probe["answer"])
    assert parsed.choice == probe["labels"][rule], (rule, probe["answer"])
    assert (parsed.status == ParseStatus.OK) == (parsed.choice is not None)


@pytest.mark.parametrize(("rule", "key"), [("viewspatial-official", "viewspatial"), ("mindcube-official", "mindcube")])
def test_the_sets_own_rules_read_the_probe_corpus_as_the_sets_code_does(rule, key):
    read = [(r["id"], read_with(rule, r["answer"]).choice) for r in replies()]
    assert read == [(r["id"], r["official_code"][key]) for r in replies()]


def test_viewspatial_official_reads_nothing_in_a_reply_ending_in_a_newline():
    assert read_with("viewspatial-official", "B\n").choice is None and read_with("viewspatial", "B\n").choice == "B"


def test_mindcube_official_reads_a_think_block_as_text():
    reply = "<think>Maybe A. Keyboard</think>\nD"
    assert read_with("mindcube-official", reply).choice == "A" and read_with("mindcube", reply).choice == "D"


@pytest.mark.parametrize("rule", ["viewspatial", "mindcube", "3dsrbench-lmms"])
def test_each_lmms_eval_port_names_the_reasoning_tag_strip(rule):
    from povagent.plugins import get_plugin_host

    entry = get_plugin_host(()).entry("parser", rule)
    assert "reasoning-tag strip" in entry.description and "reasoning-tag strip" in entry.factory.reads


@pytest.mark.parametrize("rule", RULES)
def test_parse_reaches_every_rule(rule):
    from povagent.cli import app

    probe = next(p for p in probes() if p["id"] == "think-maybe-a-then-d")
    result = CliRunner().invoke(app, ["parse", "--parser", rule, "--choices", "A=right,B=left,C=front,D=back"], input=probe["answer"])
    assert result.exit_code == 0, result.output
    assert yaml.safe_load(result.output)["choice"] == probe["labels"][rule]

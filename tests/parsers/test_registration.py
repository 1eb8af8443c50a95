"""The built-in parsers and strategies register like any plugin, under the documented names."""

from __future__ import annotations

import importlib
from functools import cache

import pluggy
import pytest

from povagent import hookspecs
from povagent.default_plugins import DEFAULT_PLUGINS
from povagent.interfaces import Parser, Strategy

PARSERS = {
    "official",
    "active",
    "json",
    "cot",
    "rescale-1000",
    "qwen",
    "gemini",
    "molmo",
    "robopoint",
    "robopoint-official",
    "internvl",
    "choice",
    "navigate",
    "viewspatial",
    "viewspatial-official",
    "mindcube",
    "mindcube-official",
    "3dsrbench-lmms",
    "vlmevalkit-exact",
    "vlmevalkit-spatial",
    "lmms-mcq-extract",
    "lmms-mcq-extract-corrected",
    "sparbench-lmms",
    "sparbench-lmms-corrected",
    "mmsi-official",
    "mmsi-lmms",
    "omnispatial-re",
    "omnispatial-re-corrected",
    "omnispatial-json",
    "omnispatial-direct",
    "omnispatial-lmms-direct",
    "omnispatial-lmms-re",
    "vsibench",
    "vsibench-lmms",
    "vlmevalkit-vsibench",
}
STRATEGIES = {
    "active",
    "basic",
    "cot",
    "spatial-cot",
    "o-plot",
    "oa-plot",
    "geometric",
    "probe-anchor",
    "probe-observer",
    "choice",
    "choice-or-number",
    "navigate",
}


@cache
def registered(hook: str) -> dict:
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    for name in DEFAULT_PLUGINS:
        if name.startswith(("povagent_plugins.parsers.", "povagent_plugins.strategies.")):
            pm.register(importlib.import_module(name), name=name)
    pm.check_pending()
    found: dict = {}

    def register(name, factory, description=""):
        assert name not in found, f"{name} registered twice"
        assert description, f"{name} has no description"
        found[name] = factory

    getattr(pm.hook, hook)(register=register)
    return found


def test_every_built_in_parser_is_registered():
    parsers = registered("register_parsers")
    assert set(parsers) == PARSERS
    assert all(isinstance(factory(), Parser) for factory in parsers.values())


def test_every_built_in_strategy_is_registered():
    strategies = registered("register_strategies")
    assert set(strategies) == STRATEGIES
    assert all(isinstance(factory(), Strategy) for factory in strategies.values())


@pytest.mark.parametrize("name", sorted(PARSERS))
@pytest.mark.parametrize(
    "text", ["", "\x00\x01", "{" * 5000, "}" * 10, "<point x=>", "[(,)]", '{"x": "1e999", "y": 1}', '{"selected_image": 1, "x": 1%s, "y": 1}' % ("0" * 400)]
)
def test_no_parser_raises_on_hostile_text(name, text):
    from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, frame_answer_schema

    spec = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
    parsed = registered("register_parsers")[name]().parse(text, spec)
    # none of these texts holds a usable point: whatever the parser makes of it, it is typed,
    # never a valid answer, and a non-answer says why
    assert isinstance(parsed, ParsedAnswer) and isinstance(parsed.status, ParseStatus)
    assert parsed.status not in (ParseStatus.OK, ParseStatus.REPAIRED), parsed
    if not parsed.answered:
        assert parsed.reason and parsed.x is None and parsed.y is None


ANSWER_ALPHABET = '{}[]()<>"\':,.-\u2212 \n0123456789xyselctd_imagpontbx=/`'


def test_no_parser_raises_on_generated_text():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from povagent.answers.spec import AnswerSpec, frame_answer_schema

    spec = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
    parsers = {name: registered("register_parsers")[name]() for name in sorted(PARSERS)}

    # every parser reads each generated text: each still reads 150 of them, and hypothesis
    # makes the 150 once instead of once a parser (making them was most of the test's CPU)
    @settings(max_examples=150, deadline=None, database=None)
    @given(st.text(alphabet=ANSWER_ALPHABET, max_size=120))
    def check(text):
        for name, parser in parsers.items():
            parsed = parser.parse(text, spec)
            assert parsed.answered == (parsed.x is not None and parsed.status != "unparseable"), (name, parsed)

    check()

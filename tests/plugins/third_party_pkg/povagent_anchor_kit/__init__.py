"""A third party's povagent plugin package, written as its author would (nothing of povagent
edited, installed by its ``povagent`` entry point): the ``anchor-point`` answer type with a
strategy and parser asking for it, the ``anchor-check`` scorer declaring two metrics, and the
``about_face`` active-mode tool. The end-to-end test ``tests/plugins/test_third_party_package.py``
installs it and runs it."""

from __future__ import annotations

from povagent import hookimpl
from povagent_anchor_kit.answer import ANCHOR_POINT, AnchorJsonParser, AnchorStrategy
from povagent_anchor_kit.scorer import AnchorCheckScorer
from povagent_anchor_kit.tool import ABOUT_FACE


@hookimpl
def register_answer_types(register) -> None:
    register("anchor-point", ANCHOR_POINT, description=ANCHOR_POINT.description)


@hookimpl
def register_strategies(register) -> None:
    register("anchor-basic", AnchorStrategy, description="anchor kit: the basic prompt, asking for an anchor-point")


@hookimpl
def register_parsers(register) -> None:
    register("anchor-json", AnchorJsonParser, description="anchor kit: the json parser, reading anchor-points too")


@hookimpl
def register_scorers(register) -> None:
    register("anchor-check", AnchorCheckScorer, description="anchor kit: is the point on the anchor object")


@hookimpl
def register_tools(register) -> None:
    register("about_face", ABOUT_FACE)

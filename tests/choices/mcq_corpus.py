"""The probe corpus of multiple-choice replies (mcq_corpus.yaml) and the labels the upstream rules give."""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import yaml

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.plugins import get_plugin_host

CORPUS = Path(__file__).with_name("mcq_corpus.yaml")
# libyaml's loader where PyYAML was built with it: the same corpus, read ~8x faster (every
# xdist worker reads it while collecting)
FAST_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


@cache
def corpus() -> dict[str, Any]:
    """The corpus file as written by the upstream run (its header says how)."""
    return yaml.load(CORPUS.read_text(encoding="utf-8"), Loader=FAST_LOADER)


def replies() -> list[dict[str, Any]]:
    """Every probe reply with its upstream labels."""
    return corpus()["replies"]


def reply_ids() -> list[str]:
    """The replies' ids, for test ids."""
    return [reply["id"] for reply in replies()]


def options() -> tuple[tuple[str, str], ...]:
    """The options every probe reply answers."""
    return tuple((label, text) for label, text in corpus()["options"])


def choice_spec() -> AnswerSpec:
    """The answer spec of the corpus's question."""
    labels = [label for label, _ in options()]
    return AnswerSpec(schema={"type": "object", "properties": {"choice": {"enum": labels}}}, asks_frame=False, choices=options())


def read_with(parser: str, reply: str) -> ParsedAnswer:
    """``reply`` read by the registered parser ``parser``."""
    return get_plugin_host(()).parser(parser, {}).parse(reply, choice_spec())

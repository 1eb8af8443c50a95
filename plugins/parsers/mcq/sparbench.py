"""The ``sparbench-lmms`` parser: what lmms-eval's SPAR-Bench ``exact_match`` credits, and its correction.

lmms-eval's SPAR-Bench task (``exact_match`` of ``lmms_eval/tasks/sparbench/utils.py``) scores a
multiple-choice reply against the gold letter with no parsing step: after lmms-eval's reasoning
strip, both lower-cased, a hit when the reply equals the gold, or the reply occurs inside the
gold, or the reply's first character equals the gold. For a one-letter gold that is: the
reply's first character is the gold letter ("Because..." is ``B``), or the reply is empty (the
empty string occurs inside every gold). These are the known bugs.

- ``sparbench-lmms`` gives the first character, upper-cased, as the label; an empty reply gives
  no label with the reason :data:`EMPTY_REPLY`, which the ``choice-sparbench`` scorer counts as
  a hit, as lmms-eval does.
- ``sparbench-lmms-corrected`` reads a label only when the reply is one (``b``, ``B.``) or opens
  with one standing alone (``B. left``, ``B) left``); an empty reply reads nothing. Score it
  with ``choice``.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL

#: The reason an empty reply carries; ``choice-sparbench`` scores it a hit (the upstream bug).
EMPTY_REPLY = "empty reply (SPAR-Bench's exact_match scores it correct whatever the gold)"
_OPENING_LABEL = re.compile(r"([A-Za-z])(?![A-Za-z0-9])")


def sparbench_label(reply: str) -> str | None:
    """The letter SPAR-Bench's ``exact_match`` compares with a one-letter gold: the first character."""
    reply = strip_reasoning_blocks(reply)
    if not reply:
        return None
    # lmms-eval lower-cases both sides; upper-casing an ASCII letter is the same comparison
    return reply[0].upper() if reply[0].isascii() else reply[0]


def sparbench_corrected_label(reply: str) -> str | None:
    """A letter only where the reply is one, or opens with one standing alone."""
    found = _OPENING_LABEL.match(strip_reasoning_blocks(reply))
    return found.group(1).upper() if found else None


class SparBenchLmmsParser(RuleParser):
    """The first character, as SPAR-Bench's ``exact_match`` credits it (module docstring)."""

    reads = "the reply's first character, upper-cased (lmms-eval's SPAR-Bench exact_match, bugs included)"
    beside_official = "reads choice answers, which the official (point) parser does not read; with choice-sparbench an empty reply is a hit"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The first character; an empty reply says :data:`EMPTY_REPLY`."""
        if spec.choices and not strip_reasoning_blocks(text or ""):
            return unparseable(EMPTY_REPLY)
        return super().parse(text, spec)

    rule = staticmethod(sparbench_label)


class SparBenchLmmsCorrectedParser(RuleParser):
    """A label the reply is, or opens with standing alone (module docstring)."""

    reads = "a letter that is the whole reply or opens it standing alone (SPAR-Bench exact_match, corrected)"
    beside_official = "reads choice answers, which the official (point) parser does not read; corrected reading of sparbench-lmms"

    rule = staticmethod(sparbench_corrected_label)


@hookimpl
def register_parsers(register) -> None:
    """Contribute SPAR-Bench's reading and its correction."""
    where = f"lmms_eval/tasks/sparbench/utils.py exact_match @ {LMMS_EVAL}"
    register(
        "sparbench-lmms", SparBenchLmmsParser, description=f"lmms-eval's SPAR-Bench exact_match, bugs included: the first character is the label ({where})"
    )
    register(
        "sparbench-lmms-corrected",
        SparBenchLmmsCorrectedParser,
        description=f"lmms-eval's SPAR-Bench exact_match, corrected: a letter the reply is or opens with standing alone ({where})",
    )

"""The ``mindcube`` parser: MindCube's official answer cascade, as lmms-eval's ``mindcube`` task runs it.

The rule (``extract_answer`` of lmms-eval's ``lmms_eval/tasks/mindcube/utils.py``, taken from
MindCube's ``src/evaluation/core/extractors.py``), after lmms-eval's reasoning strip: the first
step that finds a capital ``A``-``E`` gives it (lower case is never read).

1. the last ``X.`` anywhere;
2. inside an ``<Answer>`` section (up to the next ``<`` or the end): "my answer is X", "my
   answer is X.", "the answer is X", "X." (an ``Answer: `` prefix allowed), X standing alone;
   the last hit of the first pattern with one;
3. in the whole reply, in order: "X. words" followed by a line end, period or quote; "X. words";
   X opening a line (then a period, space or the end); X between ``*``/``"`` marks; "Answer X";
   "my answer is X"; "my answer is X."; "answer is X"; the last hit of the first with one;
4. the last line holding "X. words";
5. from the bottom line up, the first X standing alone.

So "A chair blocks the view, so the answer is B." is ``B`` (step 1: its last ``X.`` is ``B.``;
the article is never read), and "The answer is c" is no label (lower case).
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, MINDCUBE

_LABEL_PERIOD = re.compile(r"([A-E])\.")
_ANSWER_SECTION = re.compile(r"<Answer>(.*?)(?:<|$)", re.DOTALL)
_IN_SECTION = tuple(re.compile(p) for p in (
    r"[Mm]y answer is ([A-E])",
    r"[Mm]y answer is ([A-E])\.",
    r"[Tt]he answer is ([A-E])",
    r"(?:Answer: )?([A-E])\.",
    r"\b([A-E])\b",
))  # fmt: skip
_IN_WHOLE = tuple(re.compile(p) for p in (
    r"(?:Answer: )?([A-E])\. [A-Za-z0-9 \-\(\)\'\",]+(?=(?:\n|$|\.|\"))",
    r"(?:Answer: )?([A-E])\. [A-Za-z0-9 \-\(\)\'\"]+",
    r"(?:^|\n)(?:Answer: )?([A-E])(?:\.|$|\s)",
    r"[\*\"]([A-E])[\*\"]",
    r"\bAnswer:?\s*([A-E])\b",
    r"[Mm]y answer is ([A-E])",
    r"[Mm]y answer is ([A-E])\.",
    r"answer is ([A-E])",
))  # fmt: skip
_LABEL_WITH_WORDS = re.compile(r"([A-E])\. [A-Za-z0-9 \-\(\)\'\",]+")
_LONE_LABEL = re.compile(r"\b([A-E])\b")


def _last_hit(patterns: tuple[re.Pattern[str], ...], text: str) -> str | None:
    """The last hit of the first pattern that has one."""
    for pattern in patterns:
        hits = pattern.findall(text)
        if hits:
            return hits[-1]
    return None


def mindcube_label(text: str) -> str | None:
    """The label MindCube's cascade reads in ``text`` (module docstring), or ``None``."""
    text = strip_reasoning_blocks(text)
    if not text:
        return None
    if hits := _LABEL_PERIOD.findall(text):
        return hits[-1]
    section = _ANSWER_SECTION.search(text)
    if section and (label := _last_hit(_IN_SECTION, section.group(1))):
        return label
    if label := _last_hit(_IN_WHOLE, text):
        return label
    lines = text.split("\n")
    with_words = [hit.group(1) for line in lines if (hit := _LABEL_WITH_WORDS.search(line))]
    if with_words:
        return with_words[-1]
    for line in reversed(lines):
        if hit := _LONE_LABEL.search(line):
            return hit.group(1)
    return None


class MindCubeParser(RuleParser):
    """MindCube's cascade (module docstring)."""

    reads = "MindCube's five-step cascade over capital A-E (the set's official rule, lmms-eval's mindcube)"
    beside_official = "reads choice answers, which the official (point) parser does not read; MindCube's own rule"

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The rule's label."""
        return mindcube_label(text)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the mindcube parser."""
    register("mindcube", MindCubeParser, description=(
        f"MindCube's official answer cascade (lmms-eval lmms_eval/tasks/mindcube/utils.py extract_answer @ {LMMS_EVAL}; "
        f"= {MINDCUBE} src/evaluation/core/extractors.py)"))  # fmt: skip

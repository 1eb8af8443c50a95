"""The ``mindcube`` parser: MindCube's answer cascade, as lmms-eval's ``mindcube`` task runs it (after
lmms-eval's reasoning-tag strip; the set's own evaluator, with no strip, is ``mindcube-official``).

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

``mindcube-official`` is the same cascade as MindCube's own evaluator runs it
(``src/evaluation/evaluator.py``: ``extract_answer`` on the reply as written): no reasoning block
is removed, so ``"<think>Maybe A. Keyboard</think>\nD"`` reads ``A`` (step 1 finds ``A.`` in the
block), where lmms-eval, having removed the block, reads ``D``.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, MINDCUBE

_LABEL_PERIOD = re.compile(r"([A-E])\.")
_ANSWER_SECTION = re.compile(r"<Answer>(.*?)(?:<|$)", re.DOTALL)
_IN_SECTION = tuple(
    re.compile(p)
    for p in (
        r"[Mm]y answer is ([A-E])",
        r"[Mm]y answer is ([A-E])\.",
        r"[Tt]he answer is ([A-E])",
        r"(?:Answer: )?([A-E])\.",
        r"\b([A-E])\b",
    )
)
_IN_WHOLE = tuple(
    re.compile(p)
    for p in (
        r"(?:Answer: )?([A-E])\. [A-Za-z0-9 \-\(\)\'\",]+(?=(?:\n|$|\.|\"))",
        r"(?:Answer: )?([A-E])\. [A-Za-z0-9 \-\(\)\'\"]+",
        r"(?:^|\n)(?:Answer: )?([A-E])(?:\.|$|\s)",
        r"[\*\"]([A-E])[\*\"]",
        r"\bAnswer:?\s*([A-E])\b",
        r"[Mm]y answer is ([A-E])",
        r"[Mm]y answer is ([A-E])\.",
        r"answer is ([A-E])",
    )
)
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
    """The label lmms-eval's copy of MindCube's cascade reads in ``text``: after lmms-eval's
    reasoning-tag strip (module docstring), or ``None``."""
    return mindcube_cascade(strip_reasoning_blocks(text))


def mindcube_cascade(text: str) -> str | None:
    """The label MindCube's five-step cascade reads in ``text`` as given (no strip of any kind:
    MindCube's own evaluator calls it so), or ``None``."""
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

    reads = "lmms-eval's mindcube: its reasoning-tag strip (<think>, <analysis> blocks), then MindCube's five-step cascade over capital A-E"
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's port of MindCube's rule"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    #: lmms-eval's overall counts every question (MindCube's own leaves translation out)
    harness_sets = (("mindcube", "choice"),)

    rule = staticmethod(mindcube_label)


class MindCubeOfficialParser(RuleParser):
    """MindCube's own evaluator: the cascade on the reply as it is, no reasoning block removed."""

    reads = "MindCube's own evaluator: the five-step cascade over capital A-E on the reply as written (a <think> block is read like any text)"
    beside_official = "reads choice answers, which the official (point) parser does not read; MindCube's own rule, the set's default"
    source = MINDCUBE
    harness = "MindCube"

    rule = staticmethod(mindcube_cascade)


@hookimpl
def register_parsers(register) -> None:
    """Contribute MindCube's own rule and lmms-eval's port of it."""
    register(
        "mindcube-official",
        MindCubeOfficialParser,
        description=(
            f"MindCube's own answer reading: its five-step cascade on the reply as written, no reasoning strip, so "
            f"'<think>Maybe A. Keyboard</think>\\nD' reads A ({MINDCUBE} src/evaluation/core/extractors.py extract_answer, "
            f"as src/evaluation/evaluator.py calls it)"
        ),
    )
    register(
        "mindcube",
        MindCubeParser,
        description=(
            f"lmms-eval's MindCube rule: lmms-eval's reasoning-tag strip (--reasoning_tags <think>, <analysis>), then MindCube's "
            f"answer cascade (lmms_eval/tasks/mindcube/utils.py extract_answer @ {LMMS_EVAL}); the set's own reading is mindcube-official"
        ),
    )

"""Replies another harness logged, as ``povagent rescore-log`` reads them: one :class:`LoggedReply`
a question, whatever the harness wrote.

lmms-eval's ``--log_samples`` JSONL (:mod:`.lmms_eval_log`) and VLMEvalKit's prediction file
(:mod:`.vlmevalkit_log`) each become a :class:`HarnessLog`: the replies as the model wrote them,
what the harness's own filter made of them where it kept both, each question's options, gold label
and category, and one :class:`~povagent.dataset.problems.Problem` line (file, line or row, field)
per record that cannot be scored; the rest are still read. A log is untrusted: only the file the
user named is opened (a regular file, links followed, nothing beside it), its size, its lines and
its replies are bounded, and nothing in it is run or looked up.

This module holds what the readers share; it never scores (that is :mod:`povagent.run.rescore_log`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from povagent.dataset.problems import Problem
from povagent.results.plugin_errors import MAX_REPLY_CHARS as PARSED_REPLY_CHARS

#: The largest log read (a 5,000-question run with long reasoning replies is well under it).
MAX_LOG_BYTES = 1 << 30
#: The longest record line of a JSONL log (a question's reply, prompt and metrics).
MAX_LOG_LINE_BYTES = 16 << 20
#: The longest reply kept: what a parser is handed at most (a longer one is a bad record, named).
MAX_REPLY_CHARS = PARSED_REPLY_CHARS
#: The most records read: the sets hold at most a few tens of thousands of questions.
MAX_RECORDS = 1_000_000
#: The longest record name (``doc_id``, ``index``) kept: a table and a disagreement quote it.
MAX_ITEM_CHARS = 200
#: The most options a question may have (labels ``A``-``Z``).
MAX_OPTIONS = 26


@dataclass(frozen=True, slots=True)
class LoggedReply:
    """One question of a log: the model's reply and what the question needs to score it."""

    #: The record as the harness names it (lmms-eval's ``doc_id``, VLMEvalKit's ``index``).
    item: str
    #: Where it is in the file (``line 12``, ``row 12``): how a problem or a disagreement names it.
    where: str
    #: The reply as the model wrote it (lmms-eval's ``resps``, VLMEvalKit's ``prediction``).
    reply: str
    #: The options, ``(label, text)``, in the order shown (texts may be empty where the log
    #: keeps only the labels).
    options: tuple[tuple[str, str], ...]
    #: The gold label.
    gold: str
    category: str = ""
    #: The broader type of ``category`` where the set has one (3DSRBench's ``orientation``).
    main_category: str = ""
    #: The question id copies of one question share a stem of (3DSRBench's ``qid``); default
    #: ``item``.
    question_id: str = ""
    #: What the harness's own filter made of the reply before its rule read it (lmms-eval's
    #: ``filtered_resps``: its reasoning-tag strip), where the log keeps it apart from ``reply``.
    filtered: str | None = None
    #: The gold number of a numerical question (VSI-Bench's counts and distances): ``options``
    #: is then empty and ``gold`` the number as logged.
    gold_number: float | None = None


@dataclass
class HarnessLog:
    """A log as read: its replies, the records left out, and which fields the replies came from."""

    file: Path
    harness: str
    replies: list[LoggedReply] = field(default_factory=list)
    problems: list[Problem] = field(default_factory=list)
    #: The field holding the reply as the model wrote it (``resps``, ``prediction``).
    reply_field: str = ""
    #: The field holding the harness's filtered reply (``filtered_resps``), or ``""``.
    filtered_field: str = ""
    #: The field holding the gold answer (lmms-eval's ``target``, VLMEvalKit's ``answer``).
    gold_field: str = "target"
    #: What a reader of the numbers must know about the log as a whole (one sentence each).
    notes: list[str] = field(default_factory=list)

    @property
    def stripped(self) -> int:
        """How many replies the harness's filter changed (``filtered`` kept and different)."""
        return sum(1 for r in self.replies if r.filtered is not None and r.filtered != r.reply)


_LABEL_AT_START = re.compile(r"\s*\(?([A-Z])(?:[\.\):]|\s|$)")
_STANDALONE = re.compile(r"(?<![A-Za-z0-9])([A-Z])(?![A-Za-z0-9])")
_OPTION_LINE = re.compile(r"^\s*(?:(?:Choices|Options)\s*:\s*)?\(?([A-Z])[\.\)]\s*(.*?)\s*$", re.IGNORECASE)


def gold_label(answer: str) -> str | None:
    """The label a gold cell names: ``"B"``, ``"(B)"``, ``"B. left"`` give ``B``, as does what
    follows the last ``<answer>`` (MindCube's ``grounded_output``, ``<think>...</think><answer>B.
    left</answer>``); else the first capital letter standing alone (``"The answer is B"``);
    ``None`` when there is none."""
    text = answer.strip()
    if "<answer>" in text:
        text = text.rsplit("<answer>", 1)[1].strip()
    if found := _LABEL_AT_START.match(text):
        return found.group(1)
    found = _STANDALONE.search(text)
    return found.group(1) if found else None


def options_in_prompt(prompt: str) -> tuple[tuple[str, str], ...]:
    """The options a prompt lists one a line (``A. right``, ``(B) left``, ``Choices: A. right``):
    the longest run of lines labelled ``A``, ``B``, ``C``... in order; else the options one line
    lists after ``Options:`` (``Options: A: left, B: right``, as MMSI-Bench writes them inside
    its questions); ``()`` when there is neither."""
    from povagent.dataset.choice_sets.mmsi_records import inline_options

    best: list[tuple[str, str]] = []
    run: list[tuple[str, str]] = []
    for line in prompt.splitlines():
        found = _OPTION_LINE.match(line)
        label = found.group(1).upper() if found else None
        if label is not None and found is not None and label == chr(ord("A") + len(run)):
            run.append((label, found.group(2)))
        elif label == "A" and found is not None:
            run = [("A", found.group(2))]
        else:
            run = []
        if len(run) > len(best):
            best = list(run)
    if not best:  # the last line naming options inline; the prompt's instructions follow on their own lines
        line = next((line for line in reversed(prompt.splitlines()) if "Options:" in line), "")
        return inline_options(line)[:MAX_OPTIONS]
    return tuple(best[:MAX_OPTIONS])


#: The last gold label a question whose options the log does not list may have (``Q`` is no
#: option of any set these logs come from: such a record is named, not scored).
UNLISTED_LAST = "H"


def with_gold(options: tuple[tuple[str, str], ...], gold: str) -> tuple[tuple[str, str], ...]:
    """``options``, or, where the log lists none, the labels ``A`` up to the gold one (at least
    ``A``-``D``; a gold past :data:`UNLISTED_LAST` gets ``A``-``D``, and the caller names the
    record) with empty texts: every rule reads labels; only VLMEvalKit's reads texts too."""
    if options:
        return options
    last = max(ord("D"), ord(gold)) if len(gold) == 1 and "A" <= gold <= UNLISTED_LAST else ord("D")
    return tuple((chr(c), "") for c in range(ord("A"), last + 1))


def gold_number(answer: str) -> float | None:
    """The number a gold cell holds (``"3"``, ``"2.5"``), if finite; ``None`` for anything else."""
    try:
        number = float(answer.strip())
    except ValueError:
        return None
    return number if math.isfinite(number) else None


def checked_reply(value: object) -> str | None:
    """A reply cell as text, or ``None`` when it is no text or longer than :data:`MAX_REPLY_CHARS`."""
    if not isinstance(value, str) or len(value) > MAX_REPLY_CHARS:
        return None
    return value


__all__ = ["HarnessLog", "LoggedReply", "gold_label", "gold_number", "options_in_prompt", "with_gold"]

"""OmniSpatial's answer rules: the set's own four ``--eval_type`` readings and lmms-eval's two tasks'.

The set's own (``process_info`` of ``api_eval.py`` at the commit :data:`~.upstream.OMNISPATIAL`
names; the gold is ``chr(65 + answer)``, a hit is the label read equal to it):

- ``omnispatial-re`` (``--eval_type re``, the script's default and the set's default here): the
  LAST ``Answer: X`` (``Answer``, optional spaces, a colon, optional spaces, a letter ``A``-``D``
  ending a word), matched in either case and kept as written: "answer: b" reads ``b``, which
  is never the gold ``B``. **A reply with no such line counts as ``A``**, so a blank or a
  refusal scores on every question whose gold is A. Reproduced under the rule's name; the
  parse then says so (status ``repaired``, ``repair`` naming the fallback).
- ``omnispatial-re-corrected``: the same reading where a reply with no such line is no answer.
- ``omnispatial-json`` (``--eval_type json``): the reply stripped, a leading ```` ```json ````
  and a trailing ```` ``` ```` removed, stripped again, parsed as JSON; its ``answer`` field
  (``A`` when absent) stripped, upper-cased, first character. Any failure (not JSON, not an
  object, a non-text ``answer``) reads ``A``, as upstream catches every exception.
- ``omnispatial-direct`` (``--eval_type direct``): the first character of the stripped reply,
  upper-cased ("Answer: B" reads ``A``; "The answer is B" reads ``T``, never a gold).
- ``llm`` (``--eval_type llm``): a judge model (GPT-4.1-mini) says ``True`` or ``False`` to the
  reply against the gold letter. No rule reproduces a judge offline: no parser here bears its
  name, and the how-to says so.

lmms-eval's two tasks (lmms-eval's reasoning-tag strip first, as for every lmms-eval task):

- ``omnispatial-lmms-direct`` (task ``omni_spatial``, ``lmms_eval/tasks/omni_spatial/utils.py``):
  the text up to and including the first ``</think>`` removed, then up to the first
  ``</thought>``; if an ``<answer>...</answer>`` block is left (either case), only its text;
  then the first character, upper-cased.
- ``omnispatial-lmms-re`` (task ``omnispatial_test``, ``lmms_eval/tasks/omnispatial/utils.py``,
  its default ``eval_type: re``): the set's ``re`` rule, fallback ``A`` included.
"""

from __future__ import annotations

import json
import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, OMNISPATIAL

#: The label OmniSpatial's ``re`` and ``json`` rules read where they read nothing.
FALLBACK = "A"
# possessive: whitespace can never be the colon or the letter after it, so giving none back
# reads the same labels, in linear time on a reply of many "answer"s and long runs of spaces
_ANSWER_LINE = re.compile(r"Answer\s*+:\s*+([A-D])\b", re.IGNORECASE)
_THINK_PREFIX = re.compile(r"^.*?</think>", re.DOTALL)
_THOUGHT_PREFIX = re.compile(r"^.*?</thought>", re.DOTALL)
_ANSWER_OPEN = re.compile(r"<answer>", re.IGNORECASE)
_ANSWER_CLOSE = re.compile(r"</answer>", re.IGNORECASE)


def omnispatial_re_label(text: str) -> str | None:
    """The letter of the last ``Answer: X`` in ``text``, as written; ``None`` where there is none
    (the set's rule then reads :data:`FALLBACK`)."""
    hits = _ANSWER_LINE.findall(text)
    return hits[-1] if hits else None


def omnispatial_json_label(text: str) -> str | None:
    """What the set's ``json`` rule reads in ``text``: the ``answer`` field's first character,
    upper-cased, :data:`FALLBACK` on any failure; ``None`` for an empty ``answer``."""
    cleaned = text.strip().removeprefix("```json").removesuffix("```").strip()
    try:
        answer = json.loads(cleaned).get("answer", FALLBACK)
        letter = answer.strip().upper()[:1]
    except Exception:  # upstream's own catch-all: whatever fails reads A
        return FALLBACK
    return letter or None


def omnispatial_direct_label(text: str) -> str | None:
    """The first character of ``text`` stripped, upper-cased (``None``: a blank reply)."""
    return text.strip()[:1].upper()[:1] or None


def _lmms_strip_think(text: str) -> str:
    """lmms-eval ``omni_spatial``'s ``_strip_think``: the reasoning before the first ``</think>``
    and ``</thought>`` removed, then the inside of the first ``<answer>`` block that closes, or
    the text stripped. The block is found in two scans (a lazy pattern retried at every
    ``<answer>`` takes quadratic time): the first opening tag with a closing tag after it is
    the first opening tag, when any closing tag follows it."""
    text = _THOUGHT_PREFIX.sub("", _THINK_PREFIX.sub("", text, count=1), count=1)
    opening = _ANSWER_OPEN.search(text)
    closing = _ANSWER_CLOSE.search(text, opening.end()) if opening else None
    if opening and closing:
        return text[opening.end() : closing.start()].strip()
    return text.strip()


def omnispatial_lmms_direct_label(text: str) -> str | None:
    """What lmms-eval's ``omni_spatial`` task reads in ``text`` (module docstring), or ``None``."""
    return omnispatial_direct_label(_lmms_strip_think(strip_reasoning_blocks(text)))


class _FallbackParser(RuleParser):
    """A rule that reads :data:`FALLBACK` where it finds nothing (``fallback`` on), as OmniSpatial's does."""

    fallback = True
    fallback_reason = "no 'Answer: X' in the reply: OmniSpatial's re rule reads it as A"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The rule's label; where it reads none, ``A`` marked ``repaired`` (or no answer, corrected)."""
        parsed = super().parse(text, spec)
        if parsed.choice is None and spec.choices and self.fallback:
            return ParsedAnswer(status=ParseStatus.REPAIRED, choice=FALLBACK, span=(text or "")[:200] or None, repair=self.fallback_reason)
        return parsed


class OmniSpatialReParser(_FallbackParser):
    """OmniSpatial's ``re`` rule, no-line-reads-A included (module docstring)."""

    reads = "OmniSpatial's re rule: the last 'Answer: X' (A-D, either case, kept as written); a reply with none reads A"
    beside_official = "reads choice answers, which the official (point) parser does not read; OmniSpatial's own default rule, the set's default"
    source = OMNISPATIAL
    harness = "OmniSpatial"

    rule = staticmethod(omnispatial_re_label)


class OmniSpatialReCorrectedParser(OmniSpatialReParser):
    """OmniSpatial's ``re`` rule where a reply with no ``Answer: X`` is no answer."""

    fallback = False
    reads = "OmniSpatial's re rule corrected: the last 'Answer: X' (A-D, either case, kept as written); a reply with none is no answer"
    beside_official = "reads choice answers, which the official (point) parser does not read; OmniSpatial's re rule without its read-A fallback"
    no_label_reason = "no 'Answer: X' in the reply"
    harness = "OmniSpatial, corrected"
    #: beside the set's own re rule in a second opinion: how much its read-A fallback adds
    harness_sets = (("omnispatial", "choice"),)


class OmniSpatialJsonParser(RuleParser):
    """OmniSpatial's ``json`` rule (module docstring); its ``A`` on failure is the label it reads."""

    reads = "OmniSpatial's json rule: the JSON reply's answer field, first character upper-cased; A on any failure"
    beside_official = "reads choice answers, which the official (point) parser does not read; OmniSpatial's --eval_type json"

    rule = staticmethod(omnispatial_json_label)


class OmniSpatialDirectParser(RuleParser):
    """OmniSpatial's ``direct`` rule (module docstring)."""

    reads = "OmniSpatial's direct rule: the stripped reply's first character, upper-cased"
    beside_official = "reads choice answers, which the official (point) parser does not read; OmniSpatial's --eval_type direct"

    rule = staticmethod(omnispatial_direct_label)


class OmniSpatialLmmsDirectParser(RuleParser):
    """lmms-eval's ``omni_spatial`` task (module docstring)."""

    reads = "lmms-eval's omni_spatial: its reasoning-tag strip, the task's own </think>/</thought>/<answer> strip, then the first character upper-cased"
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's omni_spatial task"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    harness_sets = (("omnispatial", "choice"),)

    rule = staticmethod(omnispatial_lmms_direct_label)


class OmniSpatialLmmsReParser(_FallbackParser):
    """lmms-eval's ``omnispatial_test`` task: the set's ``re`` rule after lmms-eval's strip."""

    reads = "lmms-eval's omnispatial_test: its reasoning-tag strip, then the last 'Answer: X' (A-D, either case, as written); none reads A"
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's omnispatial_test task"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    harness_sets = (("omnispatial", "choice"),)

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The rule's label."""
        return omnispatial_re_label(strip_reasoning_blocks(text))


@hookimpl
def register_parsers(register) -> None:
    """Contribute OmniSpatial's own rules, the corrected re rule, and lmms-eval's two tasks' rules."""
    source = f"{OMNISPATIAL} api_eval.py process_info"
    register(
        "omnispatial-re",
        OmniSpatialReParser,
        description=(
            f"OmniSpatial's own default rule (--eval_type re): the last 'Answer: X', A-D in either case kept as written; "
            f"a reply with none reads A, marked repaired ({source}); omnispatial-re-corrected reads none as no answer"
        ),
    )
    register(
        "omnispatial-re-corrected",
        OmniSpatialReCorrectedParser,
        description=(f"OmniSpatial's re rule corrected: the last 'Answer: X'; a reply with none is no answer, not A (after {source})"),
    )
    register(
        "omnispatial-json",
        OmniSpatialJsonParser,
        description=(f"OmniSpatial's --eval_type json: the JSON reply's answer field, first character upper-cased; A on any failure ({source})"),
    )
    register(
        "omnispatial-direct",
        OmniSpatialDirectParser,
        description=(f"OmniSpatial's --eval_type direct: the stripped reply's first character, upper-cased ({source})"),
    )
    register(
        "omnispatial-lmms-direct",
        OmniSpatialLmmsDirectParser,
        description=(
            f"lmms-eval's omni_spatial task: reasoning-tag strip, its own </think>, </thought> and <answer> strip, then the first "
            f"character upper-cased (lmms_eval/tasks/omni_spatial/utils.py omni_spatial_process_results @ {LMMS_EVAL})"
        ),
    )
    register(
        "omnispatial-lmms-re",
        OmniSpatialLmmsReParser,
        description=(
            f"lmms-eval's omnispatial_test task (eval_type re): reasoning-tag strip, then the last 'Answer: X'; none reads A "
            f"(lmms_eval/tasks/omnispatial/utils.py omnispatial_process_results @ {LMMS_EVAL})"
        ),
    )

"""MMSI-Bench's answer rules: the set's own (``mmsi-official``, the set's default) and lmms-eval's
``mmsi_bench`` task's (``mmsi-lmms``). VLMEvalKit's ``MMSIBench`` reads replies with its
spatial-bench rule: the ``vlmevalkit-spatial`` parser with the ``choice-vlmevalkit`` scorer.

``mmsi-official`` (``extract_single_choice_with_word_boundary`` and ``evaluate`` of
``vlmeval/dataset/mmsi_bench.py`` in the authors' VLMEvalKit fork, at the commit
:data:`~.upstream.MMSI_BENCH` names), on the reply as written:

1. if the reply holds text between double backticks (````X````), only the first such text is
   read further;
2. then, if what is read holds text between single backticks, only the first such text;
3. the first capital ``A``-``D`` standing alone as a word and *not* followed by a space and a
   letter is the label ("A bike is on the left, so B" reads ``B``: the article is skipped);
   none: no label.

The set's ``evaluate`` counts a hit when the label, lower-cased, equals the gold ``answer``
lower-cased and stripped; the gold being one capital letter, that is label == gold. (The
set's README prints a version with a ``{X}`` step between 2 and 3; the code at the pinned
commit has none, and the code is what scored the paper's table.)

``mmsi-lmms`` (``extract_single_choice_with_word_boundary`` and ``msr_process_results`` of
lmms-eval's ``lmms_eval/tasks/mmsi_bench/utils.py``): lmms-eval's reasoning-tag strip, the two
backtick steps, then the first text between braces, then the first ``A``-``F`` in *either*
case standing alone and not followed by a space and a letter, upper-cased. So "the answer is
b" reads ``B`` here and nothing in the set's own rule, and "E" is a label here only.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, MMSI_BENCH

_DOUBLE_BACKTICKS = re.compile(r"``([^`]*)``")
_SINGLE_BACKTICKS = re.compile(r"`([^`]*)`")
_BRACES = re.compile(r"\{([^}]*)\}")
#: a letter standing alone, unless an article: a space and a letter after it
_OFFICIAL_LETTER = re.compile(r"\b[A-D]\b(?!\s[a-zA-Z])")
_LMMS_LETTER = re.compile(r"\b[A-F]\b(?!\s[a-zA-Z])", re.IGNORECASE)


def _enclosed(pattern: re.Pattern[str], text: str) -> str:
    """The first text ``pattern`` encloses in ``text``, else ``text`` unchanged."""
    found = pattern.search(text)
    return found.group(1) if found else text


def mmsi_official_label(text: str) -> str | None:
    """The label MMSI-Bench's own rule reads in ``text`` (module docstring), or ``None``."""
    text = _enclosed(_SINGLE_BACKTICKS, _enclosed(_DOUBLE_BACKTICKS, text))
    found = _OFFICIAL_LETTER.search(text)
    return found.group() if found else None


def mmsi_lmms_label(text: str) -> str | None:
    """The label lmms-eval's ``mmsi_bench`` task reads in ``text`` (module docstring), or ``None``."""
    text = strip_reasoning_blocks(text)
    text = _enclosed(_BRACES, _enclosed(_SINGLE_BACKTICKS, _enclosed(_DOUBLE_BACKTICKS, text)))
    found = _LMMS_LETTER.search(text)
    return found.group().upper() if found else None


class MMSIOfficialParser(RuleParser):
    """MMSI-Bench's own rule (module docstring)."""

    reads = ("MMSI-Bench's own rule: the text in the first ``...`` then `...` if any, then the first capital A-D standing alone and not followed by a space "
             "and "
             "a letter")
    beside_official = "reads choice answers, which the official (point) parser does not read; MMSI-Bench's own rule, the set's default"
    source = MMSI_BENCH
    harness = "MMSI-Bench"

    rule = staticmethod(mmsi_official_label)


class MMSILmmsParser(RuleParser):
    """lmms-eval's ``mmsi_bench`` rule (module docstring)."""

    reads = ("lmms-eval's mmsi_bench: its reasoning-tag strip, the backtick and {...} steps, then the first A-F in either case standing alone and not followed "
             "by a space and a letter")
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's reading of MMSI-Bench"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    #: lmms-eval's mmsi_bench task: a hit is the label equal to the gold answer (msr_process_results)
    harness_sets = (("mmsi", "choice"),)

    rule = staticmethod(mmsi_lmms_label)


@hookimpl
def register_parsers(register) -> None:
    """Contribute MMSI-Bench's own rule and lmms-eval's reading of it."""
    register(
        "mmsi-official",
        MMSIOfficialParser,
        description=(
            f"MMSI-Bench's own rule: the text in ``...`` then `...` if present, then the first capital A-D word not followed by "
            f"a space and a letter ({MMSI_BENCH} vlmeval/dataset/mmsi_bench.py extract_single_choice_with_word_boundary, evaluate)"
        ),
    )
    register(
        "mmsi-lmms",
        MMSILmmsParser,
        description=(
            f"lmms-eval's MMSI-Bench rule: lmms-eval's reasoning-tag strip, the backtick and {{...}} steps, then the first A-F word in "
            f"either case not followed by a space and a letter, upper-cased (lmms_eval/tasks/mmsi_bench/utils.py "
            f"extract_single_choice_with_word_boundary @ {LMMS_EVAL}); the set's own reading is mmsi-official"
        ),
    )

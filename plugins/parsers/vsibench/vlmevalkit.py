"""The ``vlmevalkit-vsibench`` parser: VLMEvalKit's rule-based reading of VSI-Bench replies.

VLMEvalKit's ``VsiBench.evaluate`` (``vlmeval/dataset/vsibench.py`` at
open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94, no judge) loads the prediction
file with pandas, turns every ``prediction`` into text with ``str()``, and reads a
multiple-choice reply with ``can_match_option`` (the ``vlmevalkit-spatial`` rule:
:func:`~povagent_plugins.parsers.mcq.vlmevalkit_spatial.spatial_bench_label`) and a numerical one
with ``can_match_na`` (``vlmeval/dataset/utils/spatial_bench/matching_func.py``):

1. A reply written as a list literal (``"[3.5, 2]"``: it starts with ``[`` and ends with ``]``
   once stripped) is read as a Python literal and only its first item is read on, as ``str()``
   writes it; a reply that is no literal reads no number (upstream's ``except`` around it all),
   nor here one longer than :data:`MAX_LIST_CHARS` (upstream parses it, at any size).
2. Zero-width characters are dropped; the English number words ``zero`` to ``twenty`` (whole
   words, any case) become digits, so ``"twenty-one"`` reads ``"20-1"``.
3. A number opening an ``<answer ...>`` block, when only text with no ``<`` (starting with no
   digit) stands between it and ``</answer>``.
4. Else the *last* number after the last ``</think>`` (else the last ``<think>``), else the last
   number anywhere: ``[-+]?(?:\\d*\\.\\d+|\\d+)(?:[eE][-+]?\\d+)?``, so ``"1,200"`` reads 200,
   ``"3-4 m"`` reads -4 and ``"between 2 and 3 meters"`` reads 3.

Before either, the reply is what VLMEvalKit's own ``load`` hands the rule, as for every
VLMEvalKit rule (:mod:`~povagent_plugins.parsers.mcq.vlmevalkit_load`): a prediction cell pandas
reads as missing (exactly ``N/A``, ``NA``, ``NULL``, ``None``, ``nan``, empty, ...) is ``"nan"``.

Upstream's number patterns backtrack in quadratic time on long runs (an ``<answer`` with no
``>``, say); a reply is untrusted, so step 3 is written here to look at each ``>`` once, and
the probe corpus and a differential check against the upstream functions hold the two equal.
"""

from __future__ import annotations

import ast
import re
from typing import Any

from povagent import hookimpl
from povagent.answers.numeric_question import asks_number
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.interfaces import Parser
from povagent_plugins.parsers.mcq.upstream import VLMEVALKIT
from povagent_plugins.parsers.mcq.vlmevalkit_load import LOAD_FILTER, as_vlmevalkit_loads
from povagent_plugins.parsers.mcq.vlmevalkit_spatial import after_reasoning, spatial_bench_label
from povagent_plugins.parsers.vsibench.first_word import NEITHER, number_parse

#: The number words ``normalize_number_words`` turns into digits (``num2words(0)`` .. ``(20)``).
NUMBER_WORDS = (
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
    "thirteen",
    "fourteen",
    "fifteen",
    "sixteen",
    "seventeen",
    "eighteen",
    "nineteen",
    "twenty",
)
#: The longest list literal read (upstream reads any: a megabyte of list takes half a gigabyte
#: and seconds to parse); a longer one reads no number, a divergence no real reply reaches.
MAX_LIST_CHARS = 1 << 16
_WORD_VALUE = {word: str(value) for value, word in enumerate(NUMBER_WORDS)}
_NUMBER_WORD = re.compile(r"\b(" + "|".join(NUMBER_WORDS) + r")\b", re.IGNORECASE)
_ZERO_WIDTH = re.compile("[\u200b\u200c\u200d\ufeff]")
NUMBER = r"[-+]?(?:\d*\.\d+|\d+)(?:[eE][-+]?\d+)?"
_NUMBER = re.compile(NUMBER)
_DIGIT = re.compile(r"\d")  # upstream's \d (Unicode category Nd; not str.isdigit, which takes "²" too)
# step 3, an <answer ...> block opening with a number: the opening tag up to its first ">",
# then spaces and the number; what follows is checked at the next "<" (see _answer_block_number)
_ANSWER_OPEN = re.compile(r"<\s*+answer\b", re.IGNORECASE)
_NUMBER_AFTER_TAG = re.compile(rf"\s*+({NUMBER})")
_ANSWER_CLOSE = re.compile(r"<\s*+/\s*+answer\s*+>", re.IGNORECASE)


def _words_as_digits(text: str) -> str:
    """``normalize_number_words``: each whole number word ``zero``-``twenty`` as its digits (a
    word matched only through Unicode case folding, such as ``ſix``, is kept)."""
    return _NUMBER_WORD.sub(lambda found: _WORD_VALUE.get(found.group(1).lower(), found.group(0)), text)


def _answer_block_number(text: str) -> float | None:
    """Step 3: the number opening the first ``<answer ...>`` block that upstream's
    ``TAGGED_NUMERIC_ANSWER`` matches. Its tag ends at the first ``>`` after ``answer``; the
    number follows after spaces, and the block matches when ``</answer>`` opens at the first
    ``<`` after the number and the number is followed by that ``<`` or by a character that is no
    digit. A shorter reading of the number changes neither (its next ``<`` is the same, and a
    digit after it blocks it), so each ``>`` decides once: tags sharing one share the outcome."""
    tag_end = -1
    for opening in _ANSWER_OPEN.finditer(text):
        if opening.end() <= tag_end:
            continue  # the same ">" as the tag before: the same outcome
        tag_end = text.find(">", opening.end())
        if tag_end == -1:
            return None  # no later tag has a ">" either
        number = _NUMBER_AFTER_TAG.match(text, tag_end + 1)
        if number is None:
            continue
        after = number.end()
        bracket = text.find("<", after)
        if bracket == -1 or (bracket > after and _DIGIT.match(text, after)):
            continue
        if _ANSWER_CLOSE.match(text, bracket):
            return float(number.group(1))
    return None


def _last_number(text: str) -> float | None:
    last = None
    for last in _NUMBER.finditer(text):  # noqa: B007 - the last match is the one read
        pass
    return float(last.group(0)) if last is not None else None


def _first_listed(reply: str) -> str | None:
    """The text step 1 reads on: the first item of a list literal as ``str()`` writes it, the
    reply itself where it is no list or an empty one; ``None`` where upstream's literal read
    fails (it then reads no number), and where the reply is longer than :data:`MAX_LIST_CHARS`."""
    if not (reply.strip().startswith("[") and reply.strip().endswith("]")):
        return reply
    if len(reply) > MAX_LIST_CHARS:
        return None
    try:
        items: Any = ast.literal_eval(reply)  # a literal only: nothing in the reply is run
        return str(items[0]) if isinstance(items, list) and items else reply
    except Exception:  # upstream's own except: a reply it cannot read is no number
        return None


def vlmevalkit_number(reply: str) -> float | None:
    """The number ``can_match_na`` reads in ``reply`` (module docstring, steps 1-4), or ``None``."""
    raw = _first_listed(reply)
    if raw is None:
        return None
    text = _words_as_digits(_ZERO_WIDTH.sub("", raw.strip()))
    try:
        tagged = _answer_block_number(text)
        if tagged is not None:
            return tagged
        after = _last_number(after_reasoning(text))
        return after if after is not None else _last_number(text)
    except (ValueError, OverflowError):  # upstream's except: float() of a number too long to convert
        return None


class VlmevalkitVSIBenchParser(Parser):
    """VLMEvalKit's reading of VSI-Bench (module docstring)."""

    answer_types = frozenset({"choice", "number", "choice-or-number"})
    reads = "VLMEvalKit's VsiBench: a letter as its spatial-bench rule reads one (can_match_option), the last number after the reasoning (can_match_na)"
    beside_official = "reads choice and number answers, which the official (point) parser does not read; VLMEvalKit's reading of VSI-Bench, no judge"
    source = VLMEVALKIT
    harness = "VLMEvalKit"
    harness_filter = LOAD_FILTER
    #: VLMEvalKit's VsiBench scores with compute_mcq_score and compute_na_score, and averages
    #: the question types as its own _aggregate does: the vsibench-vlmevalkit scorer
    harness_sets = (("vsibench", "vsibench-vlmevalkit"),)

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """A letter (a question with options) or a number; never raises."""
        reply = as_vlmevalkit_loads(text or "")
        if spec.choices:
            label = spatial_bench_label(reply)
            if label is None:
                return unparseable("the rule reads no option letter (VLMEvalKit's False)", span=reply[:200] or None)
            return ParsedAnswer(status=ParseStatus.OK, choice=label, span=reply[:200])
        if asks_number(spec.required_keys):
            return number_parse(vlmevalkit_number(reply), reply)
        return unparseable(NEITHER)


@hookimpl
def register_parsers(register) -> None:
    """Contribute VLMEvalKit's reading of VSI-Bench."""
    register(
        "vlmevalkit-vsibench",
        VlmevalkitVSIBenchParser,
        description=(
            "VLMEvalKit's VSI-Bench rule, no judge: can_match_option for an option letter, can_match_na (the last number after "
            f"the reasoning, number words to twenty read) for a number (vlmeval/dataset/vsibench.py, "
            f"utils/spatial_bench/matching_func.py @ {VLMEVALKIT}); the set's own reading is vsibench"
        ),
    )

"""The ``vlmevalkit-spatial`` parser: VLMEvalKit's rule-based reading for its spatial benchmarks.

VLMEvalKit's spatial-bench scoring without a judge (``compute_mcq_score`` in
``vlmeval/dataset/utils/spatial_bench/cal_scores.py``) reads the reply with
``can_match_option`` (``matching_func.py``) given no options, so the letters read are ``A``-``F``
whatever the question offers. No reasoning block is removed first; the rule looks at them
itself. Zero-width characters are dropped and the reply stripped; then the first step that
reads a letter gives it, upper-cased:

1. an ``<answer ...>`` block opening with a letter ``A``-``J`` (any case, optional punctuation);
2. in the last 800 characters, a letter (optionally bracketed) right before ``</answer>``, else
   right before ``</think>``;
3. the last six non-empty lines after the last ``</think>`` (else the last ``<think>``), from
   the bottom, skipping lines that start "option X:": a line that is a single letter ``A``-``F``
   in any case (markdown and brackets around it allowed); a line opening "X." / "X)" / "X:" and
   a space; a line whose capital ``A``-``F`` standing alone are all one letter;
4. the same on the last six lines of the last 800 characters;
5. the first "final answer" / "the answer is" / "answer" / "correct answer" (and their Chinese
   forms), an optional separator and bracket, then a letter (any case);
6. when the capital letters standing alone (bracketed or not) in the lines that are not
   "option X:" lines are all one letter, that letter.

Nothing read is ``False`` upstream; here no label. The reply is first what VLMEvalKit's ``load``
makes of it (:mod:`.vlmevalkit_load`: ``"N/A"`` is ``"nan"``, no letter).
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent_plugins.parsers.mcq.upstream import VLMEVALKIT
from povagent_plugins.parsers.mcq.vlmevalkit_load import VlmevalkitRuleParser

#: The letters ``compute_mcq_score`` reads (``can_match_option`` with no options).
LETTERS = "ABCDEF"
TAIL_LINES = 6
TAIL_CHARS = 800

_ZERO_WIDTH = re.compile("[\u200b\u200c\u200d\ufeff]")

# Upstream's patterns backtrack in quadratic (and, for the concluding phrase, worse) time on long
# runs of spaces or markdown; a reply is untrusted, so each is written here in a form that reads
# the same letters in linear time: a possessive quantifier (``*+``) where the next token can never
# match what it gave back, and the letter-finding patterns reduced to the conditions that decide
# them (each reduction says why it is the same). The probe corpus and a differential check against
# the upstream functions hold the two equal.

# step 1, an <answer ...> block: the opening tag, then (after the first ">") the letter
_ANSWER_OPEN = re.compile(r"<\s*+answer\b", re.IGNORECASE)
_LETTER_AFTER_TAG = re.compile(r"\s*+([A-Ja-j])", re.IGNORECASE)
_ANSWER_CLOSE = re.compile(r"<\s*+/\s*+answer\s*+>", re.IGNORECASE)
# step 2, a letter right before </answer> or </think> (only ever run on the 800-character tail)
_OPEN = r"[\(\[\{（【]?\s*"
_CLOSE = r"[\)\]\}）】]?"
_BEFORE_ANSWER_END = re.compile(rf"(?<![A-Za-z]){_OPEN}([{LETTERS}])\s*{_CLOSE}\s*</\s*answer\s*>", re.IGNORECASE)
_BEFORE_THINK_END = re.compile(rf"(?<![A-Za-z]){_OPEN}([{LETTERS}])\s*{_CLOSE}\s*</\s*think\s*>", re.IGNORECASE)
_THINK_END = re.compile(r"</\s*+think\s*+>", re.IGNORECASE)
_THINK_START = re.compile(r"<\s*+think\s*+>", re.IGNORECASE)
# steps 3 and 4, line by line
_OPTION_LINE = re.compile(r"^(?:[*_>\-\s]*)(?:option|选项)\s+[A-J]\s*[:：]", re.IGNORECASE)
_SINGLE_LETTER_LINE = re.compile(r"^\s*+[*_`>（）\[\]【】\(\)]*+\s*+([A-Fa-f])\s*+[*_`（）\[\]【】\(\)]*+\s*+$")
_LABELLED_LINE = re.compile(r"^\s*([A-F])\s*[\.．:：\)\]】、-]\s+", re.IGNORECASE)
_TIGHT = r"\.,:;!?\)\]】》」』，。；、：）】》」』"
# Upstream allows markdown and spaces before the letter and after it; what decides a letter is
# only that no ASCII letter precedes it (the symbols before it may be read as none) and that,
# after optional closing markdown, a line end, a space or tight punctuation follows.
_INLINE_CAPITAL = re.compile(rf"(?<![A-Za-z])([A-F])(?=[*_`）\]\}})]*(?:$|[\s{_TIGHT}]))")
# step 5, a concluding phrase (the spaces before the letter possessive; after it, as upstream)
_CONCLUSION = re.compile(
    r"(?i)(?:final\s*+answer|the\s*+answer\s*+is|answer(?:\s*+is)?|correct\s*+answer|答案|最终答案|结论|所以|因此|我选(?:择)?|选择|选)"
    rf"\s*+[:：>＝=]?\s*+[\(\[\{{（【]?\s*+([{LETTERS}])\s*{_CLOSE}(?:\b|[.)、。])"
)
# step 6: upstream allows a bracket and spaces either side of the letter; what decides it is only
# that no ASCII letter touches it on either side.
_LONE_CAPITAL = re.compile(rf"(?<![A-Za-z])([{LETTERS}])(?![A-Za-z])")


def _answer_block_letter(text: str) -> str | None:
    """Step 1: the letter opening the first ``<answer ...>`` tag that has one, when a closing
    ``</answer>`` follows it. A later opening tag's letter can only sit further on, so when no
    closing tag follows the first, none follows any; tags sharing a ``>`` share their letter, so
    each ``>`` is looked for, and read after, once."""
    tag_end = -1
    for opening in _ANSWER_OPEN.finditer(text):
        if opening.end() <= tag_end:
            continue  # the same ">" and the same (missing) letter as the tag before
        tag_end = text.find(">", opening.end())
        if tag_end == -1:
            return None
        if letter := _LETTER_AFTER_TAG.match(text, tag_end + 1):
            return letter.group(1) if _ANSWER_CLOSE.search(text, letter.end()) else None
    return None


def _from_last_lines(lines: list[str]) -> str | None:
    """Steps 3 and 4 on a list of lines: the bottom-most line that names one letter."""
    for line in reversed([line.strip() for line in lines if line.strip()]):
        if _OPTION_LINE.search(line):
            continue
        if alone := _SINGLE_LETTER_LINE.fullmatch(line):
            return alone.group(1).upper()
        if labelled := _LABELLED_LINE.match(line):
            return labelled.group(1).upper()
        capitals = {capital.upper() for capital in _INLINE_CAPITAL.findall(line)}
        if len(capitals) == 1:
            return capitals.pop()
    return None


def after_reasoning(text: str) -> str:
    """What follows the last ``</think>``, else the last ``<think>``, stripped; else all of ``text``
    (where VLMEvalKit's spatial-bench and VsiBench readings look past the reasoning)."""
    for tag in (_THINK_END, _THINK_START):
        ends = [found.end() for found in tag.finditer(text)]
        if ends:
            return text[ends[-1] :].strip()
    return text


def spatial_bench_label(reply: str) -> str | None:
    """The letter VLMEvalKit's spatial-bench rule reads in ``reply`` (module docstring), or ``None``."""
    text = _ZERO_WIDTH.sub("", reply.strip())
    if block := _answer_block_letter(text):
        return block.upper()
    tail = text[-TAIL_CHARS:]
    for closing in (_BEFORE_ANSWER_END, _BEFORE_THINK_END):
        if anchored := closing.search(tail):
            return anchored.group(1).upper()
    for lines in (after_reasoning(text).splitlines(), tail.splitlines()):
        if picked := _from_last_lines(lines[-TAIL_LINES:]):
            return picked
    if concluded := _CONCLUSION.search(text):
        return concluded.group(1).upper()
    kept = "\n".join(line for line in text.splitlines() if not _OPTION_LINE.search(line))
    capitals = set(_LONE_CAPITAL.findall(kept))
    return capitals.pop() if len(capitals) == 1 else None


class VlmevalkitSpatialParser(VlmevalkitRuleParser):
    """VLMEvalKit's spatial-bench rule (module docstring)."""

    reads = ("an `<answer>` block, a letter before `</answer>` or `</think>`, the last lines, a concluding phrase, else one lone capital A-F (VLMEvalKit "
             "spatial bench)")
    beside_official = "reads choice answers, which the official (point) parser does not read; VLMEvalKit's spatial-bench reading without a judge"
    no_label_reason = "the rule reads no option letter (VLMEvalKit's False)"
    #: VLMEvalKit's ViewSpatialBench, MindCubeBench, MMSIBench and OmniSpatialBench score with
    #: compute_mcq_score (no judge)
    harness_sets = (
        ("viewspatial", "choice-vlmevalkit"),
        ("mindcube", "choice-vlmevalkit"),
        ("mmsi", "choice-vlmevalkit"),
        ("omnispatial", "choice-vlmevalkit"),
    )

    rule = staticmethod(spatial_bench_label)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the vlmevalkit-spatial parser."""
    register(
        "vlmevalkit-spatial",
        VlmevalkitSpatialParser,
        description=(
            f"VLMEvalKit's spatial-bench rule, no judge: can_match_option with no options "
            f"(vlmeval/dataset/utils/spatial_bench/matching_func.py, cal_scores.py compute_mcq_score @ {VLMEVALKIT})"
        ),
    )

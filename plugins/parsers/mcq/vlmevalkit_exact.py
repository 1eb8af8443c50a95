"""The ``vlmevalkit-exact`` parser: VLMEvalKit's reading of a multiple-choice reply with no judge model.

With ``--judge exact_matching`` VLMEvalKit reads a reply with ``can_infer`` only
(``vlmeval/utils/matching_util.py``; ``extract_answer_from_item`` of
``vlmeval/dataset/utils/multiple_choice.py``), and a reply it cannot read becomes ``Z``, a
label no question has, so a wrong answer. No reasoning block is removed. The steps:

1. A reply holding VLMEvalKit's API-failure message reads no option by label (step 5 still runs);
   one holding one of its four refusal sentences ("Cannot determine the answer", ...) is ``Z``.
2. Each of ``.()[],:;!*#{}`` becomes a space and the reply splits on whitespace. When exactly
   one option label is among the words, that label, if its first occurrence is among the last
   four words; when no label is but a word ``Z`` is, ``Z``.
3. Else "answer is X" (optionally "correct answer is", X optionally in ``**``, any case) for
   X in ``A``-``D`` that the options carry.
4. Else (and after an API failure) the option texts: a reply longer than twice the options'
   total text length reads nothing; else the one option whose text (lower case) occurs in
   the lower-cased reply, if exactly one does.
5. Nothing read: ``Z``.

``Z`` is no label here (``choice`` is ``None``, the reason says ``Z``). VLMEvalKit reads an
extra word count when the ``VERBOSE`` environment variable is set; the default (unset) is
reproduced. Option labels must be capital letters, as VLMEvalKit asserts. The reply is first
what VLMEvalKit's ``load`` makes of it (:mod:`.vlmevalkit_load`: ``"None"`` is ``"nan"``), and
the options are those its ``build_choices`` keeps (an option whose text pandas reads as missing,
such as ``"None"``, is no choice). A question whose options all go reads ``Z``.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable
from povagent_plugins.parsers.mcq.upstream import VLMEVALKIT
from povagent_plugins.parsers.mcq.vlmevalkit_load import VlmevalkitRuleParser, options_as_vlmevalkit_loads

#: VLMEvalKit's marker of a reply it never got.
API_FAILURE = "Failed to obtain answer via API"
#: Replies VLMEvalKit reads as a refusal (``Z``).
REFUSALS = (
    "Sorry, I can't help with images of people yet.",
    "I can't process this file.",
    "I'm sorry, but without the image provided",
    "Cannot determine the answer",
)
_SPACED = str.maketrans(dict.fromkeys(".()[],:;!*#{}", " "))
_ANSWER_IS = re.compile(r"(?i)(?:correct\s+)?answer\s+is\s+\**([ABCD])\**")
#: What VLMEvalKit writes for "no option".
NO_OPTION = "Z"


def _by_label(reply: str, labels: tuple[str, ...]) -> str | None:
    """Steps 1-3: a label, ``Z``, or ``None`` (go on to the option texts)."""
    if API_FAILURE in reply:
        return None
    if any(refusal in reply for refusal in REFUSALS):
        return NO_OPTION
    words = reply.translate(_SPACED).split()
    present = [label for label in labels if label in words]
    if len(present) == 1 and words.index(present[0]) > len(words) - 5:
        return present[0]
    if not present and NO_OPTION in words:
        return NO_OPTION
    stated = _ANSWER_IS.search(reply)
    if stated and stated.group(1).upper() in labels:
        return stated.group(1).upper()
    return None


def _by_text(reply: str, options: tuple[tuple[str, str], ...]) -> str | None:
    """Step 4: the single option whose text the (short enough) reply holds."""
    reply = reply.lower()
    if len(reply) > 2 * sum(len(text) for _, text in options):
        return None
    holding = [label for label, text in options if text.lower() in reply]
    return holding[0] if len(holding) == 1 else None


def vlmevalkit_exact_label(reply: str, options: tuple[tuple[str, str], ...]) -> str:
    """VLMEvalKit's exact-matching reading of ``reply`` (module docstring): a label, or ``Z``."""
    labels = tuple(label for label, _ in options)
    return _by_label(reply, labels) or _by_text(reply, options) or NO_OPTION


class VlmevalkitExactParser(VlmevalkitRuleParser):
    """VLMEvalKit's exact-matching rule (module docstring)."""

    reads = "one option letter among the last words, else 'answer is X', else one option's text; else Z (VLMEvalKit, no judge)"
    beside_official = "reads choice answers, which the official (point) parser does not read; VLMEvalKit's reading without a judge"
    no_label_reason = f"the rule reads {NO_OPTION} (VLMEvalKit's no-option label, scored wrong)"
    #: VLMEvalKit's ``_3DSRBench`` reads with exact matching (its authors' rule: the set's official one), and so does its
    #: ``MMSIBench_circular`` (``ImageMCQDataset.evaluate_heuristic``: ``mcq_circular_eval`` with no judge)
    harness_sets = (("3dsrbench", "choice-3dsrbench"), ("mmsi-circular", "choice-mmsi-circular"))

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The rule's label; options not labelled by capital letters are refused, as VLMEvalKit asserts."""
        if not all(len(label) == 1 and "A" <= label <= "Z" for label, _ in spec.choices):
            return unparseable("VLMEvalKit's rule reads options labelled by single capital letters only")
        return super().parse(text, spec)

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The rule's label; ``None`` for ``Z``."""
        label = vlmevalkit_exact_label(text, options_as_vlmevalkit_loads(spec.choices))
        return None if label == NO_OPTION else label


@hookimpl
def register_parsers(register) -> None:
    """Contribute the vlmevalkit-exact parser."""
    register(
        "vlmevalkit-exact",
        VlmevalkitExactParser,
        description=(f"VLMEvalKit's exact-matching rule, no judge: can_infer, else Z (vlmeval/utils/matching_util.py @ {VLMEVALKIT})"),
    )

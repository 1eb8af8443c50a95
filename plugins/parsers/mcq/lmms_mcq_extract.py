"""The ``lmms-mcq-extract`` parser: lmms-eval's shared multiple-choice reader, and its corrected reading.

lmms-eval's ``extract_mcq_answer`` (``lmms_eval/tasks/_task_utils/mcq_extract.py``) serves
several of its tasks. After lmms-eval's reasoning strip it trims ``,.!?;:'"`` from both ends,
pads the reply with a space each side and collects candidates, each an option label with a
position and a kind, then keeps the kind ranked highest and, within it, the latest position:

- ``start`` (10): the trimmed reply opens with the label, not followed by a letter;
- ``end`` (9): it ends with the label, not preceded by a letter;
- ``phrase`` (7): after the first occurrence (any case) of each answer phrase ("the answer is",
  "i choose", "my answer is", ... and Korean, Chinese and Japanese ones), the first occurrence
  of *every* label anywhere after it, inside a word or not;
- ``(X)`` (6), ``X.`` (5), ``X:`` (4), ``X)`` (3), ``X `` (2): the last occurrence of each;
- only when there is no candidate at all: the last occurrence of each label, even inside a word.

The ``phrase`` kind is the known bug: "The answer is C. Because..." holds a phrase candidate
``C`` and a later one, the ``B`` of "Because", so it reads ``B``. ``lmms-mcq-extract-corrected``
keeps everything else and takes, after each phrase, only the first label standing alone (no
letter or digit either side): the label the phrase names.
"""

from __future__ import annotations

from typing import NamedTuple

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL

#: The phrases after which a label is taken as the answer, in lmms-eval's order.
ANSWER_PHRASES = (
    "the answer is",
    "answer is",
    "the correct answer is",
    "correct answer is",
    "the best answer is",
    "best answer is",
    "the correct option is",
    "correct option is",
    "the best option is",
    "best option is",
    "the choice is",
    "choice is",
    "the correct choice is",
    "correct choice is",
    "i choose",
    "i select",
    "i pick",
    "my answer is",
    "my choice is",
    "옵션",
    "정답은",
    "답은",
    "답:",
    "答案是",
    "答案为",
    "选",
    "答えは",
)
#: Kinds of candidate by rank (higher wins), and the text after the label that marks each
#: suffix kind.
RANK = {"start": 10, "end": 9, "phrase": 7, "parentheses": 6, "period": 5, "colon": 4, "right_paren": 3, "space": 2, "fallback": 0}
_SUFFIX_KINDS = (("period", "."), ("colon", ":"), ("right_paren", ")"), ("space", " "))


class Candidate(NamedTuple):
    """One label the reply may mean, where, and in which form."""

    label: str
    position: int
    kind: str


def _standalone(text: str, at: int, width: int) -> bool:
    """Whether ``text[at:at+width]`` has no ASCII letter or digit either side."""
    before = text[at - 1] if at > 0 else " "
    after = text[at + width] if at + width < len(text) else " "
    return not (before.isascii() and before.isalnum()) and not (after.isascii() and after.isalnum())


def _phrase_candidates(text: str, labels: tuple[str, ...], corrected: bool) -> list[Candidate]:
    """The ``phrase`` candidates: upstream, every label's first occurrence after each phrase;
    corrected, only the first label standing alone after it."""
    lowered = text.lower()
    found: list[Candidate] = []
    for phrase in ANSWER_PHRASES:
        at = lowered.find(phrase)
        if at == -1:
            continue
        after = at + len(phrase)
        if not corrected:
            found += [Candidate(label, text.find(label, after), "phrase") for label in labels if text.find(label, after) != -1]
            continue
        named = [
            Candidate(label, position, "phrase")
            for label in labels
            for position in _occurrences(text, label, after)
            if _standalone(text, position, len(label))
        ]
        if named:
            found.append(min(named, key=lambda candidate: candidate.position))
    return found


def _occurrences(text: str, label: str, start: int) -> list[int]:
    """Every position of ``label`` in ``text`` from ``start`` on."""
    positions = []
    at = text.find(label, start)
    while at != -1:
        positions.append(at)
        at = text.find(label, at + 1)
    return positions


def mcq_extract_label(reply: str, labels: tuple[str, ...], corrected: bool = False) -> str | None:
    """The label lmms-eval's shared reader takes from ``reply`` (module docstring), or ``None``."""
    reply = strip_reasoning_blocks(reply)
    if not reply.strip():
        return None
    trimmed = reply.strip()
    for mark in ",.!?;:'\"":
        trimmed = trimmed.strip(mark)
    text = f" {trimmed} "
    candidates = [Candidate(label, text.rfind(f"({label})"), "parentheses") for label in labels if f"({label})" in text]
    for kind, suffix in _SUFFIX_KINDS:
        candidates += [Candidate(label, text.rfind(label + suffix), kind) for label in labels if label + suffix in text]
    candidates += _phrase_candidates(text, labels, corrected)
    bare = text.strip()
    for label in labels:
        if bare.startswith(label) and (len(bare) == 1 or not bare[1].isalpha()):
            candidates.append(Candidate(label, 0, "start"))
    for label in labels:
        if bare.endswith(label) and (len(bare) == 1 or not bare[-2].isalpha()):
            candidates.append(Candidate(label, len(text) - 1, "end"))
    if not candidates:
        candidates = [Candidate(label, text.rfind(label), "fallback") for label in labels if label in text]
    if not candidates:
        return None
    return max(candidates, key=lambda candidate: (RANK[candidate.kind], candidate.position)).label


class LmmsMcqExtractParser(RuleParser):
    """lmms-eval's shared reader, bug included (module docstring)."""

    reads = "the best-ranked, latest label candidate of lmms-eval's shared mcq_extract, phrase bug included"
    beside_official = "reads choice answers, which the official (point) parser does not read; reads 'The answer is C. Because...' as B"
    corrected = False

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The rule's label among the options' labels."""
        return mcq_extract_label(text, tuple(label for label, _ in spec.choices), corrected=self.corrected)


class LmmsMcqExtractCorrectedParser(LmmsMcqExtractParser):
    """lmms-eval's shared reader with the phrase bug fixed (module docstring)."""

    reads = "lmms-eval's shared mcq_extract, but a phrase names only the first label standing alone after it"
    beside_official = "reads choice answers, which the official (point) parser does not read; corrected reading of lmms-mcq-extract"
    corrected = True


@hookimpl
def register_parsers(register) -> None:
    """Contribute lmms-eval's shared reader and its corrected reading."""
    where = f"lmms_eval/tasks/_task_utils/mcq_extract.py extract_mcq_answer @ {LMMS_EVAL}"
    register(
        "lmms-mcq-extract",
        LmmsMcqExtractParser,
        description=f"lmms-eval's shared multiple-choice reader, bug included: 'The answer is C. Because' reads B ({where})",
    )
    register(
        "lmms-mcq-extract-corrected",
        LmmsMcqExtractCorrectedParser,
        description=f"lmms-eval's shared multiple-choice reader, corrected: an answer phrase names the first label standing alone after it ({where})",
    )

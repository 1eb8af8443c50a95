"""The ``vsibench`` parser: VSI-Bench's own reading of a reply, from its first word.

VSI-Bench's code (``lmms_eval/tasks/vsibench/utils.py`` at
vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8: ``fuzzy_matching``,
``exact_match``, ``to_float``, ``vsibench_process_results``) reads only the reply's *first word*:
the text before its first space character (``split(" ")[0]``: a newline or tab does not end a
word), its trailing dots removed, then surrounding whitespace. Nothing is stripped first, so
``" A"`` reads an empty word, ``"A.\\nB"`` reads ``"A.\\nB"`` (one word: no space in it) and
``"A.\\n"`` reads ``"A."`` (its dot is not trailing when the dots are removed).

* A multiple-choice question: the word equals the gold letter, compared case-insensitively
  (``exact_match``). The parse's ``choice`` is the option label the word names in either case,
  else the word itself (no option's label, so never the gold); an empty word is no answer.
* A numerical question: Python's ``float()`` of the word (``to_float``: ``"3"``, ``"3.5"``,
  ``"1e3"``, ``"1_000"``, ``"nan"`` and ``"inf"`` read; ``"3m"``, ``"three"`` and ``"1,000"`` do
  not). A word that is no number is no answer, which VSI-Bench scores 0.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.answers.numeric_question import asks_number
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.interfaces import Parser

#: Why a question asking neither an option nor a number is not read (a point question).
NEITHER = "the question asks neither an option label nor a number"
#: The commit the rule is read at.
THINKING_IN_SPACE = "vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8"


def first_word(reply: str) -> str:
    """The word VSI-Bench reads (``fuzzy_matching``): the text before the first space, trailing
    dots removed, then stripped of whitespace."""
    return reply.split(" ")[0].rstrip(".").strip()


def word_number(word: str) -> float | None:
    """``float(word)``, or ``None`` where Python reads no number in it (``to_float``)."""
    try:
        return float(word)
    except ValueError:
        return None


def choice_parse(word: str, spec: AnswerSpec) -> ParsedAnswer:
    """The option whose label equals ``word`` in either case (``exact_match``), else ``word``
    itself as the choice (a label no option carries); an empty word is no answer."""
    if not word:
        return unparseable("the reply's first word is empty")
    label = next((label for label, _ in spec.choices if label.lower() == word.lower()), word)
    return ParsedAnswer(status=ParseStatus.OK, choice=label, span=word[:200])


def number_parse(number: float | None, span: str) -> ParsedAnswer:
    """A parse of ``number``; ``None`` is no answer (VSI-Bench scores it 0)."""
    if number is None:
        return unparseable("the rule reads no number", span=span[:200] or None)
    return ParsedAnswer(status=ParseStatus.OK, number=number, span=span[:200])


class VSIBenchParser(Parser):
    """VSI-Bench's own first-word rule (module docstring)."""

    answer_types = frozenset({"choice", "number", "choice-or-number"})
    reads = "VSI-Bench's own rule: the reply's first space-separated word, trailing dots removed; the option letter in any case, or float() of it"
    beside_official = "reads choice and number answers, which the official (point) parser does not read; VSI-Bench's own rule, the set's default"
    source = THINKING_IN_SPACE
    harness = "VSI-Bench"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The first word as a label (a question with options) or a number; never raises."""
        word = first_word(text or "")
        if spec.choices:
            return choice_parse(word, spec)
        if asks_number(spec.required_keys):
            return number_parse(word_number(word), word)
        return unparseable(NEITHER)


@hookimpl
def register_parsers(register) -> None:
    """Contribute VSI-Bench's own rule."""
    register(
        "vsibench",
        VSIBenchParser,
        description=(
            "VSI-Bench's own rule: the reply's first space-separated word, trailing dots removed; equals the option letter "
            f"in any case, or float() of it for a number ({THINKING_IN_SPACE} lmms_eval/tasks/vsibench/utils.py "
            "fuzzy_matching, exact_match, to_float)"
        ),
    )

"""The ``vsibench-lmms`` parser: lmms-eval's reading of VSI-Bench replies.

lmms-eval's ``vsibench`` task (``lmms_eval/tasks/vsibench/utils.py`` at
EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3) reads a multiple-choice
reply as the set's own code does (the first word, :mod:`.official`), but a number with
``extract_number``: the first number *anywhere* in the reply, a run of digits
(``-?\\d+(?:\\.\\d+)?``) or a run of English number words (``"three"``, ``"twenty-one"``,
``"three hundred and twenty-one"``), whichever starts first. So ``"There are 3 chairs"`` reads 3
here and nothing officially, and ``"1,000"`` reads 1. Before either, lmms-eval's evaluator strips
reasoning blocks (:mod:`povagent_plugins.parsers.mcq.lmms_reasoning`).
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.numeric_question import asks_number
from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable
from povagent.interfaces import Parser
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL
from povagent_plugins.parsers.vsibench.first_word import NEITHER, choice_parse, first_word, number_parse

#: The number words ``extract_number`` knows, with their values.
NUMBER_WORDS = {
    # Laid out by hand (the formatter is told to skip it): a word table read by rows (units,
    # teens, tens), not thirty lines of one entry each.
    "zero": 0, "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9,
    "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15, "sixteen": 16,
    "seventeen": 17, "eighteen": 18, "nineteen": 19, "twenty": 20, "thirty": 30, "forty": 40, "fifty": 50,
    "sixty": 60, "seventy": 70, "eighty": 80, "ninety": 90, "hundred": 100, "thousand": 1000,
}  # fmt: skip
_DIGITS = re.compile(r"-?\d+(?:\.\d+)?")
_LETTERS = re.compile(r"[a-z]+")


def extract_number(text: str) -> float | None:
    """The first number in ``text`` as lmms-eval's ``extract_number`` reads it (module docstring),
    or ``None``. Case-insensitive; ``\\d`` is Python's, so other scripts' digits count too."""
    s = text.strip().lower()
    if not s:
        return None
    digits = _DIGITS.search(s)
    run_start: int | None = None
    run: list[str] = []
    for match in _LETTERS.finditer(s):
        word = match.group(0)
        if run_start is None:
            if word in NUMBER_WORDS:
                run_start = match.start()
                run.append(word)
        elif word == "and":  # "three hundred and twenty": "and" neither ends nor adds to a run
            continue
        elif word in NUMBER_WORDS:
            run.append(word)
        else:
            break
    if digits is not None and (run_start is None or digits.start() < run_start):
        return float(digits.group(0))
    if run_start is None:
        return None
    total, current = 0, 0
    for word in run:
        value = NUMBER_WORDS[word]
        if value == 100:
            current = max(current, 1) * 100
        elif value == 1000:
            total += max(current, 1) * 1000
            current = 0
        else:
            current += value
    return float(total + current)


class VSIBenchLmmsParser(Parser):
    """lmms-eval's reading of VSI-Bench (module docstring)."""

    answer_types = frozenset({"choice", "number", "choice-or-number"})
    reads = "lmms-eval's vsibench: its reasoning-tag strip, then the first word for a letter, and the first number or number words anywhere for a number"
    beside_official = "reads choice and number answers, which the official (point) parser does not read; lmms-eval's reading of VSI-Bench"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    #: lmms-eval's vsibench task scores a question as the set does (exact_match, MRA) and
    #: averages the types as the set does (_compute_all_subscores)
    harness_sets = (("vsibench", "vsibench"),)

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The first word as a label (a question with options), else the first number anywhere."""
        reply = strip_reasoning_blocks(text or "")
        if spec.choices:
            return choice_parse(first_word(reply), spec)
        if asks_number(spec.required_keys):
            return number_parse(extract_number(reply), reply)
        return unparseable(NEITHER)


@hookimpl
def register_parsers(register) -> None:
    """Contribute lmms-eval's reading of VSI-Bench."""
    register(
        "vsibench-lmms",
        VSIBenchLmmsParser,
        description=(
            "lmms-eval's VSI-Bench rule: its reasoning-tag strip, the first word for an option letter, and extract_number "
            f"(the first number or number words anywhere) for a number (lmms_eval/tasks/vsibench/utils.py @ {LMMS_EVAL}); "
            "the set's own reading is vsibench"
        ),
    )

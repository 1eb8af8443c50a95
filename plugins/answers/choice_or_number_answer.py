"""The ``choice-or-number`` answer type: an option label or a number, as each question asks.

For a set that mixes multiple-choice and numerical questions in one run (VSI-Bench: six types
answered with a letter, four with a number, one overall over both): it answers instances asking
for a ``choice`` and those asking for a ``number`` (``also_answers``), and its value is the one
the question asked, with the ``choice`` type's or the ``number`` type's shape.
"""

from __future__ import annotations

from typing import Any, Mapping

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance
from povagent_plugins.answers.choice_answer import CHOICE
from povagent_plugins.answers.number import NUMBER


def choice_or_number_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """``{"choice": label}`` or ``{"number": x}``, whichever the parse read (``None``: neither)."""
    return CHOICE.value_of(parse) if parse.choice is not None else NUMBER.value_of(parse)


def gold_choice_or_number(instance: Instance) -> Any:
    """The gold label of a multiple-choice instance, else the gold number and unit."""
    return CHOICE.gold(instance) if instance.question is not None else NUMBER.gold(instance)


def show_choice_or_number(value: Mapping[str, Any]) -> str:
    """``option B`` or ``3.2 meters``."""
    return CHOICE.show(value) if "choice" in value else NUMBER.show(value)


CHOICE_OR_NUMBER = AnswerType(
    name="choice-or-number",
    description="an option label or a number, as each question asks (a set mixing both)",
    value_schema={"oneOf": [dict(CHOICE.value_schema), dict(NUMBER.value_schema)]},
    value_of=choice_or_number_value,
    gold=gold_choice_or_number,
    show=show_choice_or_number,
    also_answers=("choice", "number"),
    default_strategy="choice-or-number",
)


@hookimpl
def register_answer_types(register) -> None:
    """Contribute the choice-or-number answer type."""
    register(CHOICE_OR_NUMBER.name, CHOICE_OR_NUMBER, description=CHOICE_OR_NUMBER.description)

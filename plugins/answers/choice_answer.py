"""The ``choice`` answer type: one labelled option of a multiple-choice question.

Registered exactly as the ``point`` type and as a third party's would be. Its gold value is the
instance's question's gold label (:class:`povagent.answers.choice_question.ChoiceQuestion`).
"""

from __future__ import annotations

from typing import Any, Mapping

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance


def choice_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """``{"choice": label}`` of a parse that chose an option."""
    if not parse.answered or parse.choice is None:
        return None
    return {"choice": parse.choice}


def gold_label(instance: Instance) -> str:
    """The gold option label (an instance without a question asks no choice)."""
    if instance.question is None:
        raise ValueError(f"instance {instance.id} asks no multiple-choice question")
    return instance.question.gold


def show_choice(value: Mapping[str, Any]) -> str:
    """``option B``."""
    return f"option {value.get('choice')}"


CHOICE = AnswerType(
    name="choice",
    description="the label of one option of a multiple-choice question",
    value_schema={"type": "object", "properties": {"choice": {"type": "string"}}, "required": ["choice"]},
    value_of=choice_value,
    gold=gold_label,
    show=show_choice,
    # a set of choice questions named with nothing else is asked in its own wording and scored by accuracy
    default_strategy="choice",
    default_scorers=("choice",),
)


@hookimpl
def register_answer_types(register) -> None:
    """Contribute the choice answer type."""
    register("choice", CHOICE, description=CHOICE.description)

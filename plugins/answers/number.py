"""The ``number`` answer type: a number, in the unit its question names where the set gives one.

Registered exactly as the ``point`` and ``choice`` types are. Its gold value is the instance's
numeric question's gold number and unit (:class:`povagent.answers.numeric_question.NumericQuestion`); the
metrics that compare the two (mean relative accuracy, absolute and relative error) live in
:mod:`povagent.scoring.relative_accuracy`, and a set's scorer declares the ones it reports.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance


def number_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """``{"number": x}`` of a parse that read a number; a NaN or infinite one is written as
    ``null`` (JSON has no such number; the parse itself keeps it)."""
    if not parse.answered or parse.number is None:
        return None
    return {"number": parse.number if math.isfinite(parse.number) else None}


def gold_number(instance: Instance) -> dict[str, Any]:
    """``{"number": gold, "unit": unit}`` of the instance's numeric question."""
    if instance.numeric is None:
        raise ValueError(f"instance {instance.id} asks no numeric question")
    return {"number": instance.numeric.gold, "unit": instance.numeric.unit}


def show_number(value: Mapping[str, Any]) -> str:
    """``3.2`` (``3.2 meters`` with a unit); ``not a finite number`` for a NaN or infinity."""
    number = value.get("number")
    if not isinstance(number, (int, float)) or isinstance(number, bool):
        return "not a finite number"
    unit = value.get("unit")
    return f"{number:g} {unit}" if unit else f"{number:g}"


NUMBER = AnswerType(
    name="number",
    description="a number (a count, a distance, a size), in the unit the question names where it names one",
    value_schema={
        "type": "object",
        "properties": {"number": {"type": ["number", "null"]}, "unit": {"type": "string"}},
        "required": ["number"],
    },
    value_of=number_value,
    gold=gold_number,
    show=show_number,
)


@hookimpl
def register_answer_types(register) -> None:
    """Contribute the number answer type."""
    register("number", NUMBER, description=NUMBER.description)

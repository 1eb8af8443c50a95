"""The ``point`` answer type: a pixel point in one of the images shown (with the frame index for
Inferred and Stated), POVBench's answer; its gold value is the target's 3D position, which the
``official`` scorer projects into the scored frame."""

from __future__ import annotations

from typing import Any, Mapping

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance


def point_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """The frame index (``None`` for Given) and the pixel point of an answered parse."""
    if not parse.answered:
        return None
    return {"selected_image": parse.selected_image, "x": parse.x, "y": parse.y}


def target_position(instance: Instance) -> list[float]:
    """The target's 3D position (world coordinates)."""
    return [float(v) for v in instance.target]


def show_point(value: Mapping[str, Any]) -> str:
    """``(x, y) in frame k``, or ``(x, y)`` for the observer view."""
    where = f" in frame {value['selected_image']}" if value.get("selected_image") is not None else ""
    return f"({value.get('x')}, {value.get('y')}){where}"


POINT = AnswerType(
    name="point",
    description="a pixel point in one of the images shown (and the frame index for Inferred and Stated)",
    value_schema={
        "type": "object",
        "properties": {"selected_image": {"type": ["integer", "null"]}, "x": {"type": "number"}, "y": {"type": "number"}},
        "required": ["x", "y"],
    },
    value_of=point_value,
    gold=target_position,
    show=show_point,
)


@hookimpl
def register_answer_types(register) -> None:
    """Contribute the point answer type."""
    register("point", POINT, description=POINT.description)

"""The ``anchor-point`` answer type: a pixel point in one of the images shown, read as marking
the anchor object the sentence names (not the target). Its value has the point's shape (a parse
carries a frame and a point); what differs is its gold value, the anchor object's 3D position.

The strategy and parser reuse the built-in ``basic`` prompt and ``json`` reading: the prompt
still asks for the target, so the type's numbers say how far a target answer lies from the
anchor (a test of the plugin contract, not a benchmark)."""

from __future__ import annotations

from typing import Any, Mapping

from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance
from povagent_plugins.parsers.json_answer import JsonAnswerParser
from povagent_plugins.strategies.basic import BasicStrategy


def anchor_point_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """The frame index and the point of an answered parse."""
    if not parse.answered:
        return None
    return {"selected_image": parse.selected_image, "x": parse.x, "y": parse.y}


def anchor_position(instance: Instance) -> tuple[float, float, float]:
    """The gold value: the anchor object's 3D position (world coordinates)."""
    return instance.anchor_object.position.as_tuple()


def show_anchor_point(value: Mapping[str, Any]) -> str:
    return f"anchor at ({value.get('x')}, {value.get('y')}) in image {value.get('selected_image')}"


ANCHOR_POINT = AnswerType(
    name="anchor-point",
    description="a pixel point marking the anchor object in one of the images shown",
    refines="point",  # a point read another way: it answers the instances that ask for points
    value_schema={
        "type": "object",
        "properties": {"selected_image": {"type": ["integer", "null"]}, "x": {"type": "number"}, "y": {"type": "number"}},
        "required": ["x", "y"],
    },
    value_of=anchor_point_value,
    gold=anchor_position,
    show=show_anchor_point,
)


class AnchorStrategy(BasicStrategy):
    """The basic prompt, asking for an ``anchor-point``."""

    answer_type = "anchor-point"


class AnchorJsonParser(JsonAnswerParser):
    """The json reading, for point-shaped answers of either type."""

    answer_types = frozenset({"point", "anchor-point"})

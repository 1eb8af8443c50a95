"""The ``walk`` answer type: a path walked on a house's floor, ending where the walker stopped.

The ``navigate`` task's answer (:mod:`povagent_plugins.strategies.navigate`): the floor positions
``(x, z)`` of the start and of every pose after, in order. A walk answers an instance that asks
for a point (``refines="point"``): the point task's target is where the walk must end. Its gold
value is that target's 3D position; the ``navigate`` scorer reads the path and the final pose.
"""

from __future__ import annotations

from typing import Any, Mapping

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance


def walk_value(parse: ParsedAnswer) -> dict[str, Any] | None:
    """``{"path": [[x, z], ...]}`` of a parse that read a walk."""
    if not parse.answered or parse.path is None:
        return None
    return {"path": [[float(x), float(z)] for x, z in parse.path]}


def walk_target(instance: Instance) -> list[float]:
    """The target's 3D position (world coordinates): where the walk must end near."""
    return [float(v) for v in instance.target]


def show_walk(value: Mapping[str, Any]) -> str:
    """``walked 5 positions, ending at (x, z)``."""
    path = value.get("path") or []
    if not path:
        return "no walk"
    x, z = path[-1]
    return f"walked {len(path)} positions, ending at ({x:.2f}, {z:.2f})"


WALK = AnswerType(
    name="walk",
    description="a path walked on the floor, start first, ending where the walker stopped",
    value_schema={
        "type": "object",
        "properties": {"path": {"type": "array", "items": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}}},
        "required": ["path"],
    },
    value_of=walk_value,
    gold=walk_target,
    show=show_walk,
    refines="point",
)


@hookimpl
def register_answer_types(register) -> None:
    """Contribute the walk answer type."""
    register("walk", WALK, description=WALK.description)

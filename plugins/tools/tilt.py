"""``tilt(degrees)``: tilt the camera; positive looks further down, clamped to [-30, 60]."""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool, number_argument
from povagent_plugins.tools.turn import MAX_DEGREES


@dataclass(frozen=True)
class Tilt:
    """``tilt(degrees)``."""

    degrees: float


def read(args: Mapping[str, Any]) -> Tilt | InvalidCall:
    """The degrees: a finite number within :data:`~povagent_plugins.tools.turn.MAX_DEGREES`."""
    degrees = number_argument(args, "degrees", MAX_DEGREES)
    return InvalidCall(degrees) if isinstance(degrees, str) else Tilt(degrees)


def run(state: EpisodeState, call: Tilt) -> Moved:
    """The pose tilted (the pose clamps the horizon)."""
    return Moved(state.pose.tilted(call.degrees), f"tilted {call.degrees:g} degrees")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    """Up to 30 degrees either way."""
    return {"degrees": round(rng.uniform(-30, 30), 1)}


TOOL = Tool(
    description="Tilt the camera; positive looks further down. The result is clamped to [-30, 60] degrees. Returns the new view.",
    parameters={"degrees": {"type": "number", "description": "degrees, positive looks down"}},
    read=read,
    run=run,
    prose="looks further down (positive) or up, within [-30, 60]",
    explained="positive looks further down (the camera's `horizon`); the result is clamped to [-30, 60]",
    renders=True,
    explore=explore,
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``tilt``."""
    register("tilt", TOOL)

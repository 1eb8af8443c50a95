"""``turn(degrees)``: rotate in place; positive turns right (clockwise seen from above)."""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool, number_argument

#: The largest turn (or tilt) a call may ask for; beyond it the call is invalid, not clamped.
MAX_DEGREES = 3600.0


@dataclass(frozen=True)
class Turn:
    """``turn(degrees)``."""

    degrees: float


def read(args: Mapping[str, Any]) -> Turn | InvalidCall:
    """The degrees: a finite number within :data:`MAX_DEGREES`."""
    degrees = number_argument(args, "degrees", MAX_DEGREES)
    return InvalidCall(degrees) if isinstance(degrees, str) else Turn(degrees)


def run(state: EpisodeState, call: Turn) -> Moved:
    """The pose turned in place."""
    return Moved(state.pose.turned(call.degrees), f"turned {call.degrees:g} degrees")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    """Up to half a turn either way."""
    return {"degrees": round(rng.uniform(-180, 180), 1)}


TOOL = Tool(
    description="Rotate in place; positive turns right (clockwise seen from above). Returns the new view.",
    parameters={"degrees": {"type": "number", "description": "degrees, positive to the right"}},
    read=read,
    run=run,
    prose="rotates in place (positive: right)",
    explained="rotate in place; positive turns right (clockwise seen from above: the dataset's `cam_yaw` grows)",
    renders=True,
    explore=explore,
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``turn``."""
    register("turn", TOOL)

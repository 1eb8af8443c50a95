"""``move(forward, right)``: walk in the current heading; the robot stops at walls and furniture."""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool, number_argument

#: The longest step a call may ask for (metres); beyond it the call is invalid, not clamped.
MAX_METRES = 100.0


@dataclass(frozen=True)
class Move:
    """``move(forward, right)``."""

    forward: float
    right: float


def read(args: Mapping[str, Any]) -> Move | InvalidCall:
    """Both distances: finite numbers within :data:`MAX_METRES`."""
    forward, right = number_argument(args, "forward", MAX_METRES), number_argument(args, "right", MAX_METRES)
    if isinstance(forward, str) or isinstance(right, str):
        return InvalidCall(forward if isinstance(forward, str) else str(right))
    return Move(forward, right)


def run(state: EpisodeState, call: Move) -> Moved:
    """Where the robot's body gets to on the reachable floor, and whether it was stopped."""
    pose = state.pose
    dx, dz = pose.offset(call.forward, call.right)
    moved = state.floor().move(pose.x, pose.z, dx, dz)
    wanted = (call.forward**2 + call.right**2) ** 0.5
    if moved.blocked:
        said = f"moved {moved.travelled:.2f} m of {wanted:.2f} m (stopped by a wall or furniture)"
        return Moved(pose.moved_to(moved.x, moved.z), said, blocked=True)
    return Moved(pose.moved_to(moved.x, moved.z), f"moved {moved.travelled:.2f} m")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    """Mostly forward, a little sideways."""
    return {"forward": round(rng.uniform(-1.0, 2.0), 2), "right": round(rng.uniform(-1.0, 1.0), 2)}


TOOL = Tool(
    description="Move the robot (camera at 0.9 m, body radius 0.25 m) in its current heading; it stops at walls and "
    "furniture. Returns how far it got and the new view.",
    parameters={
        "forward": {"type": "number", "description": "metres ahead (negative: back)"},
        "right": {"type": "number", "description": "metres to the right (negative: left)"},
    },
    read=read,
    run=run,
    prose="walks in metres and stops at walls and furniture",
    explained="walk that many metres in the current heading; the robot's body (camera at 0.9 m, radius 0.25 m) stops at "
    "walls, door jambs and floor furniture, the obstacles the generator planned its exploration with, and never leaves "
    "the reachable floor; the result says how far it got",
    renders=True,
    explore=explore,
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``move``."""
    register("move", TOOL)

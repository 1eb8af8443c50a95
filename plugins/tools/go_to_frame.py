"""``go_to_frame(frame)``: stand where an exploration frame was taken, facing as it was."""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool


@dataclass(frozen=True)
class GoToFrame:
    """``go_to_frame(frame)``."""

    frame: int


def read(args: Mapping[str, Any]) -> GoToFrame | InvalidCall:
    """The frame's number: an integer (``3.0`` is 3), nothing else."""
    frame = args["frame"]
    if isinstance(frame, float) and frame.is_integer():
        frame = int(frame)
    if isinstance(frame, bool) or not isinstance(frame, int):
        return InvalidCall(f"frame must be an integer, got {type(args['frame']).__name__}")
    return GoToFrame(frame)


def run(state: EpisodeState, call: GoToFrame) -> Moved | InvalidCall:
    """The pose of that frame, when it was shown."""
    if not 0 <= call.frame < len(state.frames):
        return InvalidCall(f"no frame {call.frame} (frames 0-{len(state.frames) - 1})")
    return Moved(state.frames[call.frame], f"at frame {call.frame}")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    """A random frame among those shown."""
    return {"frame": rng.randrange(len(state["frames"]))}


TOOL = Tool(
    description="Stand where exploration frame `frame` was taken, facing as it was; returns that view.",
    parameters={"frame": {"type": "integer", "description": "the exploration frame's number, as labelled"}},
    read=read,
    run=run,
    prose="stands where an exploration frame was taken",
    explained="stand where exploration frame `frame` (labelled `Image frame`) was taken, facing as it was; the view equals that frame",
    renders=True,
    explore=explore,
    tasks=("point",),  # a jump would walk through walls: the navigate task walks
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``go_to_frame``."""
    register("go_to_frame", TOOL)

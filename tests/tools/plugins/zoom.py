"""A third party's active-mode tool, written as a plugin author would (nothing of povagent edited):
``zoom(factor)`` narrows the field of view, and the episode renders the narrower view."""

from __future__ import annotations

import random
from dataclasses import dataclass, replace
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool, number_argument


@dataclass(frozen=True)
class Zoom:
    factor: float


def read(args: Mapping[str, Any]) -> Zoom | InvalidCall:
    factor = number_argument(args, "factor", 8.0)
    if isinstance(factor, str):
        return InvalidCall(factor)
    return Zoom(factor) if factor >= 1.0 else InvalidCall(f"factor must be at least 1, got {factor:g}")


def run(state: EpisodeState, call: Zoom) -> Moved:
    return Moved(replace(state.pose, fov=state.pose.fov / call.factor), f"zoomed in {call.factor:g} times")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    return {"factor": round(rng.uniform(1.0, 4.0), 1)}


@hookimpl
def register_tools(register) -> None:
    register("zoom", Tool(
        description="Narrow the field of view by `factor` (at least 1); returns the new view.",
        parameters={"factor": {"type": "number", "description": "how many times narrower"}},
        read=read, run=run, prose="narrows the field of view", explained="narrow the field of view `factor` times",
        renders=True, explore=explore,
    ))  # fmt: skip

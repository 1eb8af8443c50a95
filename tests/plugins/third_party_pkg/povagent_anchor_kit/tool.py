"""The ``about_face`` active-mode tool: turn the camera round (yaw + 180 degrees); the episode
renders the view behind."""

from __future__ import annotations

import random
from dataclasses import dataclass, replace
from typing import Any, Mapping

from povagent.active.tools import EpisodeState, InvalidCall, Moved, Tool


@dataclass(frozen=True)
class AboutFace:
    """No arguments: the turn is always half a circle."""


def read(args: Mapping[str, Any]) -> AboutFace | InvalidCall:
    return AboutFace()


def run(state: EpisodeState, call: AboutFace) -> Moved:
    return Moved(replace(state.pose, yaw=(state.pose.yaw + 180.0) % 360.0), "turned round")


def explore(rng: random.Random, state: Mapping[str, Any]) -> dict[str, Any]:
    return {}


ABOUT_FACE = Tool(
    description="Turn round (180 degrees) where you stand; returns the new view.",
    parameters={},
    read=read, run=run, prose="turns round to look behind", explained="turn 180 degrees in place",
    renders=True, explore=explore,
)  # fmt: skip

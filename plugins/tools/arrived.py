"""``arrived()``: the navigate task's end; the robot says it stands where the target is.

Offered only by episodes of the navigate task (``tasks=("navigate",)``), where it takes the
place of ``answer``: the answer is the pose the robot stands in, so the call has no arguments.
"""

from __future__ import annotations

from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import Arrived, EpisodeState, Tool


def read(args: Mapping[str, Any]) -> None:
    """Nothing to read: the call takes no arguments."""
    return None


def run(state: EpisodeState, call: None) -> Arrived:
    """The arrival, wherever the robot stands (the scorer judges it)."""
    return Arrived()


TOOL = Tool(
    description="Say you have arrived: you stand within 1 m of the target and see it. Ends the episode.",
    parameters={},
    read=read,
    run=run,
    prose="says you stand within 1 m of the target, facing it so it is in view",
    explained="the navigate task's end (offered only there, instead of `answer`): the robot stands within 1 m of the target "
    "and sees it; the pose it stands in is the answer",
    ends=True,
    tasks=("navigate",),
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``arrived``."""
    register("arrived", TOOL)

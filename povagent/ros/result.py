"""What the node publishes on ``~/result`` and ``ros-replay --json`` prints: one typed answer per command.

Every command gets one :class:`CommandResult`, never silence: a goal (``ok``), a pixel without a
3D point (``no_goal``), or a typed reason it could not be answered. A command that arrives while
another is answered first gets a ``queued`` result (its place in the queue), then its own answer;
one that finds the queue full gets ``queue_full`` (it is dropped, and says so). A bug met while
answering is that command's ``internal_error``, and the next command is answered. With the
``navigate_action`` parameter set, a goal also goes to Nav2 as an action: the answer's
``navigation`` says it was ``sent`` (or why not), and a second result for the same command
follows with the action's outcome.
"""

from __future__ import annotations

import math
from enum import StrEnum

from pydantic import BaseModel, ConfigDict


class CommandStatus(StrEnum):
    """How a command ended (or where it is)."""

    #: a goal in the map frame
    OK = "ok"
    #: a keyframe and a pixel, but no 3D point (the ray misses the floor, a hole in the depth)
    NO_GOAL = "no_goal"
    #: nothing to look at yet: no frame has been kept
    NO_KEYFRAMES = "no_keyframes"
    #: the model gave no answer in time, or every attempt failed
    NO_ANSWER = "no_answer"
    #: the model answered without a usable point or frame
    UNPARSEABLE = "unparseable"
    #: the frames or cameras could not be given to the agent
    BAD_INPUT = "bad_input"
    #: the command was blank
    EMPTY_COMMAND = "empty_command"
    #: accepted, waiting behind another command
    QUEUED = "queued"
    #: refused: the command queue is full (the command is dropped; send it again later)
    QUEUE_FULL = "queue_full"
    #: answering or publishing raised an unexpected error (a bug: the node logs its traceback)
    INTERNAL_ERROR = "internal_error"


class NavigationStatus(StrEnum):
    """Where the goal sent as a ``navigate_to_pose`` action is."""

    #: the goal was sent; a second result carries the outcome
    SENT = "sent"
    #: no action server was there to take the goal
    UNAVAILABLE = "unavailable"
    #: the server refused the goal
    REJECTED = "rejected"
    #: the robot reached the goal
    SUCCEEDED = "succeeded"
    #: navigation failed (Nav2 says why in ``error_code`` / ``error_msg`` since Iron)
    ABORTED = "aborted"
    #: the goal was cancelled (by another client, or a newer goal preempted it)
    CANCELED = "canceled"


class NavigationOutcome(BaseModel):
    """The ``navigate_to_pose`` action's side of a command. ``error_code`` and ``error_msg`` are
    the action result's fields; Humble's result has neither (``None`` and ``""`` then)."""

    model_config = ConfigDict(extra="forbid")

    action: str
    status: NavigationStatus
    reason: str = ""
    error_code: int | None = None
    error_msg: str = ""


class CommandResult(BaseModel):
    """One command's answer. Pixels are continuous coordinates of the chosen keyframe's image;
    ``goal`` and ``viewpoint`` (the keyframe's camera centre) are in ``map_frame`` (metres);
    ``keyframes`` is the memory's size, ``images`` the images received so far and ``malformed``
    the malformed messages so far by kind (a robot's health at a glance); stamps are the keyframe's ``header.stamp``."""

    model_config = ConfigDict(extra="forbid")

    command: str
    status: CommandStatus
    reason: str = ""
    map_frame: str = "map"
    frame_index: int | None = None
    frame_stamp_ns: int | None = None
    frame_id: str | None = None
    pixel: tuple[float, float] | None = None
    goal: tuple[float, float, float] | None = None
    goal_method: str | None = None
    viewpoint: tuple[float, float, float] | None = None
    keyframes: int = 0
    images: int = 0
    malformed: dict[str, int] = {}
    queue_position: int | None = None
    latency_s: float = 0.0
    navigation: NavigationOutcome | None = None

    def facing_yaw(self) -> float | None:
        """The map yaw (radians, z up) from the chosen keyframe's camera (``viewpoint``) to the
        goal: the heading of ``/goal_pose``; ``None`` without a goal."""
        if self.goal is None or self.viewpoint is None:
            return None
        return math.atan2(self.goal[1] - self.viewpoint[1], self.goal[0] - self.viewpoint[0])


__all__ = ["CommandResult", "CommandStatus", "NavigationOutcome", "NavigationStatus"]

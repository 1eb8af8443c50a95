"""What an active episode leaves behind: the trajectory, the counts, the answer and its camera.

What it is for: the row of an active instance keeps this record (JSON) as its final answer, so
everything the report draws (trajectories, actions used) and everything the scorer needs (the
camera of the image answered in) is in the row, and ``score``/``rescore`` recompute offline.
``EpisodeRecord.model_json_schema()`` is its JSON Schema. What it must not do: hold image
bytes (views are named by SHA-256; their PNGs live in the run folder).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from povagent.answers.spec import AnsweredCamera

#: The version of this record's shape.
RECORD_VERSION = 1


class Step(BaseModel):
    """One tool call: the action and its arguments as sent, what came back, the pose after."""

    model_config = ConfigDict(extra="forbid")

    turn: int
    action: str
    arguments: str
    valid: bool
    observation: str
    pose: AnsweredCamera | None = None
    view: int | None = None
    sha256: str | None = None
    blocked: bool = False
    counted: bool = True


class ViewRecord(BaseModel):
    """A rendered view: its number (from 1), the PNG's SHA-256 and the camera it was taken with."""

    model_config = ConfigDict(extra="forbid")

    n: int
    sha256: str
    camera: AnsweredCamera


class EpisodeCounts(BaseModel):
    """How much of the episode was used."""

    model_config = ConfigDict(extra="forbid")

    actions: int = 0
    views: int = 0
    questions: int = 0
    blocked_moves: int = 0
    invalid_calls: int = 0
    refused_over_budget: int = 0
    turns: int = 0


class EpisodeAnswer(BaseModel):
    """The final answer: the image as named, the pixel, how it was given and that image's camera.

    ``via`` is ``answer_tool`` for the ``answer`` call, ``text`` for an answer written as the
    official JSON instead (accepted, and labelled so). ``frame`` is the exploration frame's
    index when the image is one.
    """

    model_config = ConfigDict(extra="forbid", ser_json_inf_nan="constants")

    image: str
    x: float
    y: float
    via: Literal["answer_tool", "text"]
    camera: AnsweredCamera
    frame: int | None = None


class EpisodeRecord(BaseModel):
    """One episode of the active mode, as its row keeps it."""

    model_config = ConfigDict(extra="forbid")

    kind: Literal["povagent-active-episode"] = "povagent-active-episode"
    version: int = RECORD_VERSION
    budget: int
    shown_frames: int
    start: AnsweredCamera
    steps: list[Step] = Field(default_factory=list)
    views: list[ViewRecord] = Field(default_factory=list)
    counts: EpisodeCounts = Field(default_factory=EpisodeCounts)
    answer: EpisodeAnswer | None = None
    end: str = ""
    #: Steps not kept once the record held its maximum (calls refused over the budget, mostly).
    steps_dropped: int = 0


def read_record(text: str | None) -> EpisodeRecord | None:
    """The episode record a row's final answer holds, or ``None`` when it holds none."""
    if not text or '"povagent-active-episode"' not in text[:200]:
        return None
    try:
        return EpisodeRecord.model_validate_json(text)
    except ValueError:
        return None

"""What a parser reads out of a model's answer, and what it was asked for.

Pure value types shared by strategies (which declare the :class:`AnswerSpec` they ask for),
parsers (which return a :class:`ParsedAnswer`) and scorers (which read it). No parsing here.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Any

from pydantic import BaseModel, ConfigDict, Field


class ParseStatus(StrEnum):
    """How a parse went.

    ``ok`` and ``repaired`` are answers; ``out_of_range`` is an answer too (the paper keeps
    parseable out-of-range coordinates and clamps them when scoring); ``unparseable`` is a
    non-response.
    """

    OK = "ok"
    REPAIRED = "repaired"
    OUT_OF_RANGE = "out_of_range"
    UNPARSEABLE = "unparseable"

    @property
    def answered(self) -> bool:
        """True unless nothing could be read."""
        return self is not ParseStatus.UNPARSEABLE


class AnswerSpec(BaseModel):
    """What the strategy asked the model to answer.

    ``schema`` is the JSON Schema of the requested answer (``{selected_image, x, y}`` for A/B,
    ``{x, y}`` for C); ``n_frames`` is the number of images shown (1 for C); pixels are on
    ``[0, width-1] x [0, height-1]``.
    """

    model_config = ConfigDict(frozen=True)

    json_schema: dict[str, Any] = Field(alias="schema")
    width: int = 512
    height: int = 512
    n_frames: int = 1
    asks_frame: bool = True
    #: A multiple-choice question's options as ``(label, text)`` pairs, in the order shown
    #: (empty for a point): what a choice parser reads a label among.
    choices: tuple[tuple[str, str], ...] = ()

    @property
    def required_keys(self) -> tuple[str, ...]:
        """Keys the requested JSON object must carry."""
        return tuple(self.json_schema.get("required", ()))


class AnsweredCamera(BaseModel):
    """The camera of an image an answer was given in when it is no dataset frame (a view the
    active mode rendered): position, yaw and horizon (degrees), fov, image size. Scoring
    projects the ground truth into it, so a row is re-scored offline from what it holds."""

    model_config = ConfigDict(frozen=True)

    x: float
    y: float
    z: float
    yaw: float
    horizon: float
    fov: float = 100.0
    width: int = 512
    height: int = 512


def _unset(value: Any) -> bool:
    # a field written only when set (``Field(exclude_if=...)``: pydantic's own serializer leaves
    # it out, where a wrapping serializer made each parse a Python dict first, ~3 us a row)
    return value is None


class ParsedAnswer(BaseModel):
    """A typed parse of one raw answer.

    Coordinates are pixels in the requested frame size (after any repair). ``selected_image``
    is the 0-based index of the chosen frame (A/B), ``None`` for C or when missing. ``points``
    holds every point for multi-point formats (the prediction is then their centroid; the
    official scorer also reports the error of the closest one). ``span`` is the raw text the
    answer came from; ``repair`` says how it was changed (``"rescaled 0-1000 -> pixels"``, or
    ``"selected_image 3 taken from the text"`` when the frame was read from prose, not from the
    answer's JSON: an answer the official parser would not accept). An infinite or NaN
    coordinate (kept by the ``official`` parser, as the official runner records it) is written
    to JSON as ``Infinity``/``NaN``, never turned into ``null``, so a stored row reads back as parsed."""

    model_config = ConfigDict(ser_json_inf_nan="constants", frozen=True)  # parses are shared (plugin_errors: one per repeated reply)

    status: ParseStatus
    reason: str = ""
    selected_image: int | None = None
    x: float | None = None
    y: float | None = None
    points: list[tuple[float, float]] | None = None
    span: str | None = None
    repair: str | None = None
    #: Set when the answer names an image by its camera (the active mode's rendered views and
    #: frames): it is scored in this camera, not in a frame picked by ``selected_image``.
    camera: AnsweredCamera | None = None
    #: The option label a multiple-choice answer chose (``"B"``), or ``None`` (a point answer,
    #: or a choice answer that names no option).
    choice: str | None = None
    #: The floor positions (x, z) an active episode of the navigate task walked through, start
    #: first, when it ended with an arrival (its last is where the robot arrived, and
    #: ``camera`` what it saw there); ``None`` for every other answer, and then not written, so
    #: rows of the other tasks keep their bytes.
    path: list[tuple[float, float]] | None = Field(default=None, exclude_if=_unset)
    #: The number a ``number`` answer gave (:mod:`povagent.answers.numeric_question`), as the rule read it
    #: (NaN or infinite when the reply said so: such a number is accurate at no threshold);
    #: ``None`` for every other answer, and then not written, so other rows keep their bytes.
    number: float | None = Field(default=None, exclude_if=_unset)

    @property
    def answered(self) -> bool:
        """True when the parse yields a point, a chosen option, an arrival or a number."""
        if not self.status.answered:
            return False
        return (self.x is not None and self.y is not None) or self.choice is not None or self.path is not None or self.number is not None

    @property
    def point(self) -> tuple[float, float] | None:
        """``(x, y)`` when the parse yields a point (:attr:`answered`), else ``None``."""
        if self.status.answered and self.x is not None and self.y is not None:
            return (self.x, self.y)
        return None


def unparseable(reason: str, span: str | None = None) -> ParsedAnswer:
    """A non-response with its reason."""
    return ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason=reason, span=span)


def frame_answer_schema(n_frames: int, width: int, height: int) -> dict[str, Any]:
    """JSON Schema of the A/B answer ``{"selected_image", "x", "y"}``."""
    return {
        "type": "object",
        "required": ["selected_image", "x", "y"],
        "properties": {
            "selected_image": {"type": "integer", "minimum": 0, "maximum": max(n_frames - 1, 0)},
            "x": {"type": "number", "minimum": 0, "maximum": width - 1},
            "y": {"type": "number", "minimum": 0, "maximum": height - 1},
        },
    }


def point_answer_schema(width: int, height: int) -> dict[str, Any]:
    """JSON Schema of the C answer ``{"x", "y"}``."""
    return {
        "type": "object",
        "required": ["x", "y"],
        "properties": {
            "x": {"type": "number", "minimum": 0, "maximum": width - 1},
            "y": {"type": "number", "minimum": 0, "maximum": height - 1},
        },
    }


def choice_answer_schema(labels: tuple[str, ...]) -> dict[str, Any]:
    """JSON Schema of a multiple-choice answer ``{"choice"}``: one of ``labels``."""
    return {"type": "object", "required": ["choice"], "properties": {"choice": {"enum": list(labels)}}}

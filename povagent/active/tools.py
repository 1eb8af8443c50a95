"""The tools a model may call in the active mode: their schema and the checking of a call.

What it is for: the exact names and meanings results are compared by (``go_to_frame``,
``turn``, ``tilt``, ``move``, ``ask``, ``answer``), in the OpenAI function-calling schema
litellm sends as ``tools=``, and the one place a call the model made is read. A call is
untrusted output: an unknown name, missing or extra arguments, a string where a number
belongs, NaN, Infinity or 1e308, an over-long text, all become an :class:`InvalidCall` with
one line saying what was wrong, never an exception. What it must not do: know the episode's
state (whether a frame or view exists is the episode's to check), render or move.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any

from povagent.engine.received import MAX_ARGUMENTS_CHARS

#: The longest question passed to the speaker (the longest arguments text read is the bound
#: every answer's calls are cut to: :data:`povagent.engine.received.MAX_ARGUMENTS_CHARS`).
MAX_QUESTION_CHARS = 500
#: Bounds of the numbers a call may carry (beyond them a call is invalid, not clamped).
MAX_DEGREES = 3600.0
MAX_METRES = 100.0
MAX_PIXELS = 1e6

_NUMBER = {"type": "number"}


def _function(name: str, description: str, properties: dict[str, Any]) -> dict[str, Any]:
    return {
        "type": "function",
        "function": {
            "name": name,
            "description": description,
            "parameters": {"type": "object", "properties": properties, "required": list(properties), "additionalProperties": False},
        },
    }


#: The tool schema sent with every request of an episode (names and semantics are fixed).
TOOLS: tuple[dict[str, Any], ...] = (
    _function("go_to_frame", "Stand where exploration frame `frame` was taken, facing as it was; returns that view.",
              {"frame": {"type": "integer", "description": "the exploration frame's number, as labelled"}}),
    _function("turn", "Rotate in place; positive turns right (clockwise seen from above). Returns the new view.",
              {"degrees": {**_NUMBER, "description": "degrees, positive to the right"}}),
    _function("tilt", "Tilt the camera; positive looks further down. The result is clamped to [-30, 60] degrees. "
              "Returns the new view.", {"degrees": {**_NUMBER, "description": "degrees, positive looks down"}}),
    _function("move", "Move the robot (camera at 0.9 m, body radius 0.25 m) in its current heading; it stops at "
              "walls and furniture. Returns how far it got and the new view.",
              {"forward": {**_NUMBER, "description": "metres ahead (negative: back)"},
               "right": {**_NUMBER, "description": "metres to the right (negative: left)"}}),
    _function("ask", "Ask the person who spoke a question; they say what they were doing, where, and what they faced, "
              "nothing more.", {"question": {"type": "string"}}),
    _function("answer", "Give the final answer: the pixel (x, y) of the target in an image you have seen.",
              {"image": {"type": "string", "description": "\"frame k\" for exploration frame k, \"view n\" for rendered view n"},
               "x": {**_NUMBER, "description": "pixel column"}, "y": {**_NUMBER, "description": "pixel row"}}),
)  # fmt: skip
TOOL_NAMES: tuple[str, ...] = tuple(t["function"]["name"] for t in TOOLS)
_PARAMETERS = {t["function"]["name"]: tuple(t["function"]["parameters"]["properties"]) for t in TOOLS}


@dataclass(frozen=True)
class GoToFrame:
    """``go_to_frame(frame)``."""

    frame: int


@dataclass(frozen=True)
class Turn:
    """``turn(degrees)``."""

    degrees: float


@dataclass(frozen=True)
class Tilt:
    """``tilt(degrees)``."""

    degrees: float


@dataclass(frozen=True)
class Move:
    """``move(forward, right)``."""

    forward: float
    right: float


@dataclass(frozen=True)
class Ask:
    """``ask(question)``."""

    question: str


@dataclass(frozen=True)
class Answer:
    """``answer(image, x, y)``: ``kind`` is ``frame`` or ``view``, ``number`` as written."""

    kind: str
    number: int
    x: float
    y: float

    @property
    def image(self) -> str:
        """The image as the model named it (normalised): ``frame 3``, ``view 2``."""
        return f"{self.kind} {self.number}"


@dataclass(frozen=True)
class InvalidCall:
    """A call that cannot be run: ``reason`` is the one line the model is told."""

    reason: str


Action = GoToFrame | Turn | Tilt | Move | Ask | Answer

_IMAGE = re.compile(r"^\s*(frame|view)\s*#?\s*(\d{1,6})\s*$", re.IGNORECASE)


def _number(args: dict[str, Any], key: str, bound: float) -> float | str:
    value = args[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"{key} must be a number, got {type(value).__name__}"
    if isinstance(value, int) and abs(value) > bound:  # checked as an integer: a 400-digit one has no float
        return f"{key} must lie within [-{bound:g}, {bound:g}], got an integer of {len(str(abs(value)))} digits"
    value = float(value)
    if not math.isfinite(value):
        return f"{key} must be a finite number, got {value}"
    if abs(value) > bound:
        return f"{key} must lie within [-{bound:g}, {bound:g}], got {value:g}"
    return value


def read_call(name: str, arguments: str) -> Action | InvalidCall:
    """The typed action a call names, or why it is invalid (never raises)."""
    if name not in _PARAMETERS:
        return InvalidCall(f"unknown tool {name[:40]!r} (tools: {', '.join(TOOL_NAMES)})")
    if len(arguments) > MAX_ARGUMENTS_CHARS:
        return InvalidCall(f"{name}: arguments longer than {MAX_ARGUMENTS_CHARS} characters")
    try:
        args = json.loads(arguments) if arguments.strip() else {}
    except (ValueError, RecursionError):
        return InvalidCall(f"{name}: arguments are not a JSON object")
    if not isinstance(args, dict):
        return InvalidCall(f"{name}: arguments are not a JSON object")
    wanted = _PARAMETERS[name]
    missing = [k for k in wanted if k not in args]
    extra = sorted(str(k)[:40] for k in args if k not in wanted)
    if missing or extra:
        said = [f"missing {', '.join(missing)}"] if missing else []
        said += [f"unexpected {', '.join(extra[:5])}"] if extra else []
        return InvalidCall(f"{name}: {'; '.join(said)} (takes {', '.join(wanted) or 'nothing'})")
    return _typed(name, args)


def _typed(name: str, args: dict[str, Any]) -> Action | InvalidCall:
    if name == "go_to_frame":
        frame = args["frame"]
        if isinstance(frame, float) and frame.is_integer():
            frame = int(frame)
        if isinstance(frame, bool) or not isinstance(frame, int):
            return InvalidCall(f"go_to_frame: frame must be an integer, got {type(args['frame']).__name__}")
        return GoToFrame(frame)
    if name == "ask":
        question = args["question"]
        if not isinstance(question, str):
            return InvalidCall(f"ask: question must be a string, got {type(question).__name__}")
        if len(question) > MAX_QUESTION_CHARS:
            return InvalidCall(f"ask: question longer than {MAX_QUESTION_CHARS} characters")
        return Ask(question)
    if name == "answer":
        image = args["image"]
        match = _IMAGE.match(image) if isinstance(image, str) and len(image) < 40 else None
        if match is None:
            return InvalidCall('answer: image must be "frame k" or "view n"')
        x, y = _number(args, "x", MAX_PIXELS), _number(args, "y", MAX_PIXELS)
        if isinstance(x, str) or isinstance(y, str):
            return InvalidCall(f"answer: {x if isinstance(x, str) else y}")
        return Answer(match.group(1).lower(), int(match.group(2)), x, y)
    bound = MAX_METRES if name == "move" else MAX_DEGREES
    values = [_number(args, k, bound) for k in _PARAMETERS[name]]
    problems = [v for v in values if isinstance(v, str)]
    if problems:
        return InvalidCall(f"{name}: {problems[0]}")
    numbers = [float(v) for v in values]
    if name == "move":
        return Move(numbers[0], numbers[1])
    return Turn(numbers[0]) if name == "turn" else Tilt(numbers[0])

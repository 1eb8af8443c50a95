"""``answer(image, x, y)``: the final answer, a pixel in an image the model has seen."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import Answered, EpisodeState, InvalidCall, Tool, number_argument

#: The largest pixel coordinate read (beyond it the call is invalid, not clamped).
MAX_PIXELS = 1e6

_IMAGE = re.compile(r"^\s*(frame|view)\s*#?\s*(\d{1,6})\s*$", re.IGNORECASE)


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


def read(args: Mapping[str, Any]) -> Answer | InvalidCall:
    """The image (``frame k`` or ``view n``, any case, ``#`` allowed) and a finite pixel."""
    image = args["image"]
    match = _IMAGE.match(image) if isinstance(image, str) and len(image) < 40 else None
    if match is None:
        return InvalidCall('image must be "frame k" or "view n"')
    x, y = number_argument(args, "x", MAX_PIXELS), number_argument(args, "y", MAX_PIXELS)
    if isinstance(x, str) or isinstance(y, str):
        return InvalidCall(x if isinstance(x, str) else str(y))
    return Answer(match.group(1).lower(), int(match.group(2)), x, y)


def run(state: EpisodeState, call: Answer) -> Answered | InvalidCall:
    """The answer, when its image was shown."""
    if state.image_camera(call.kind, call.number) is None:
        return InvalidCall(f"no {call.image} was shown")
    return Answered(call.image, call.x, call.y)


TOOL = Tool(
    description="Give the final answer: the pixel (x, y) of the target in an image you have seen.",
    parameters={
        "image": {"type": "string", "description": '"frame k" for exploration frame k, "view n" for rendered view n'},
        "x": {"type": "number", "description": "pixel column"},
        "y": {"type": "number", "description": "pixel row"},
    },
    read=read,
    run=run,
    prose='image is "frame k" or "view n", x and y are the target\'s pixel in that image (the JSON above, written instead, answers in a frame).',
    explained='the final answer: `"frame k"` for an exploration frame, `"view n"` for the n-th rendered view; `x, y` are pixels of that image',
    ends=True,
    tasks=("point",),  # the navigate task ends with ``arrived`` instead
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``answer``."""
    register("answer", TOOL)

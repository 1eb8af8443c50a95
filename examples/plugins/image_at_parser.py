"""A parser plugin: reads answers written in prose, such as ``Image 2 at (120, 340)``.

The point is the last ``(x, y)`` pair of the answer; when the request asked for a frame, the
frame is the last ``Image N`` (0-based, as the frames are labelled). The parser never raises:
an answer it cannot read is an ``unparseable`` parse carrying the reason, which the runner
records as a ``parse_error`` row. In a pipeline YAML::

    plugins: [image_at_parser.py]
    parser: image-at
"""

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.interfaces import Parser

POINT = re.compile(r"\(\s*(-?\d+(?:\.\d+)?)\s*,\s*(-?\d+(?:\.\d+)?)\s*\)")
# At most 9 digits: int() refuses a digit string of thousands, and a parser must not raise.
FRAME = re.compile(r"\bimage\s+(\d{1,9})\b", re.IGNORECASE)


class ImageAtParser(Parser):
    """``Image N at (x, y)``; for Given (no frame asked) just ``(x, y)``."""

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The last point (and frame) in ``text``; ``unparseable`` with a reason when missing."""
        points = POINT.findall(text)
        if not points:
            return unparseable("no (x, y) pair in the answer", span=text[:200])
        x, y = float(points[-1][0]), float(points[-1][1])
        frame = None
        if spec.asks_frame:
            frames = FRAME.findall(text)
            if not frames:
                return unparseable("no 'Image N' in the answer", span=text[:200])
            frame = int(frames[-1])
        # Out-of-range pixels are still answers (the official scorer clamps them).
        inside = 0 <= x <= spec.width - 1 and 0 <= y <= spec.height - 1
        return ParsedAnswer(
            status=ParseStatus.OK if inside else ParseStatus.OUT_OF_RANGE, selected_image=frame, x=x, y=y, span=text[:200]
        )


@hookimpl
def register_parsers(register):
    """Contribute the image-at parser."""
    register("image-at", ImageAtParser, description="Prose answers: 'Image N at (x, y)'")

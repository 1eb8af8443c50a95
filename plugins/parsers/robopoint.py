"""The ``robopoint`` parser: RoboPoint's tuple lists, ``[(0.52, 0.31), (0.55, 0.33)]``.

Values with a decimal point are fractions of the image (0-1); a tuple written with two whole
numbers is in pixels (RoboPoint's documented alternative). Several points are scored at their
centroid, all kept in ``points`` so the scorer also reports the closest one (as officially).
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.text import NUMBER, normalize_minus
from povagent.answers.validation import relative_to_pixels
from povagent.answers.spec import AnswerSpec
from povagent_plugins.parsers.native import NativeParser, NativeReading

_TUPLE = re.compile(rf"\(\s*({NUMBER})\s*,\s*({NUMBER})\s*\)")


def _is_whole(literal: str) -> bool:
    return "." not in literal


class RoboPointParser(NativeParser):
    """RoboPoint ``(x, y)`` tuples: fractions, or pixels when written as integers."""

    format_name = "RoboPoint tuple"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``(x, y)`` tuple in the text, in pixels."""
        points = []
        spans = []
        for m in _TUPLE.finditer(text):
            xs, ys = normalize_minus(m.group(1)), normalize_minus(m.group(2))
            x, y = float(xs), float(ys)
            if _is_whole(xs) and _is_whole(ys):
                points.append((x, y))
            else:
                points.append((relative_to_pixels(x, 1.0, spec.width), relative_to_pixels(y, 1.0, spec.height)))
            spans.append(m.group(0))
        if not points:
            return None
        return NativeReading(points, None, ", ".join(spans))


@hookimpl
def register_parsers(register) -> None:
    """Contribute the robopoint parser."""
    register("robopoint", RoboPointParser, description="RoboPoint [(x, y), ...] fractions (integers: pixels); centroid")

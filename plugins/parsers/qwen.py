"""The ``qwen`` parser: Qwen3-VL's grounding format, ``{"point_2d": [x, y], "label": ...}``.

Coordinates are relative, 0-1000 on each axis (x first), usually inside a ```json fence, one
object per point (a list for several: scored at the centroid). ``bbox_2d: [x1, y1, x2, y2]`` on
the same scale is read as its centre. A ``selected_image`` key in the same object names the frame.
(Qwen2.5-VL's absolute pixels of its resized input are a different convention: not read here.)
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.answers.text import NUMBER, normalize_minus
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading, read_point_objects

#: ``point_2d: [x, y]`` outside a readable object (cut-off lists, unquoted keys).
_LOOSE_POINT = re.compile(rf"point_2d\W*\[\s*({NUMBER})\s*,\s*({NUMBER})\s*\]")


class QwenParser(NativeParser):
    """Qwen3-VL ``point_2d`` / ``bbox_2d`` on 0-1000."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "Qwen3-VL's native format, `point_2d: [x, y]` (or a `bbox_2d` centre) on 0-1000, else `json`"
    beside_official = 'adds: a native format the official runner does not read'

    format_name = "Qwen point_2d"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``point_2d`` (or ``bbox_2d`` centre) in the text, in pixels."""
        w, h = spec.width, spec.height
        def xy_to_pixels(x: float, y: float) -> tuple[float, float]:
            return relative_to_pixels(x, 1000, w), relative_to_pixels(y, 1000, h)

        reading, spans = read_point_objects(text, "point_2d", "bbox_2d", xy_to_pixels)
        if not reading.points:
            for m in _LOOSE_POINT.finditer(text):
                x, y = float(normalize_minus(m.group(1))), float(normalize_minus(m.group(2)))
                reading.points.append((relative_to_pixels(x, 1000, w), relative_to_pixels(y, 1000, h)))
                spans.append(m.group(0))
        reading.span = "\n".join(spans) or None
        return reading


@hookimpl
def register_parsers(register) -> None:
    """Contribute the qwen parser."""
    register("qwen", QwenParser, description="Qwen3-VL point_2d [x, y] / bbox_2d on 0-1000")

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
from povagent.answers.text import NUMBER, coerce_index, coerce_numbers, find_objects, get_key, normalize_minus
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading

#: ``point_2d: [x, y]`` outside a readable object (cut-off lists, unquoted keys).
_LOOSE_POINT = re.compile(rf"point_2d\W*\[\s*({NUMBER})\s*,\s*({NUMBER})\s*\]")


class QwenParser(NativeParser):
    """Qwen3-VL ``point_2d`` / ``bbox_2d`` on 0-1000."""

    format_name = "Qwen point_2d"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``point_2d`` (or ``bbox_2d`` centre) in the text, in pixels."""
        w, h = spec.width, spec.height
        reading = NativeReading()
        spans = []
        for obj in find_objects(text):
            _, point = get_key(obj.value, "point_2d")
            _, box = get_key(obj.value, "bbox_2d")
            xy = coerce_numbers(point, 2)
            if xy is None and (b := coerce_numbers(box, 4)) is not None:
                xy = [(b[0] + b[2]) / 2, (b[1] + b[3]) / 2]
            if xy is None:
                continue
            reading.points.append((relative_to_pixels(xy[0], 1000, w), relative_to_pixels(xy[1], 1000, h)))
            spans.append(obj.span)
            present, frame = get_key(obj.value, "selected_image")
            if present and coerce_index(frame) is not None:
                reading.selected_image = coerce_index(frame)
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

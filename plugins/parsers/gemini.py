"""The ``gemini`` parser: Gemini 2.x / Robotics-ER points, ``[{"point": [y, x], "label": ...}]``.

Coordinates are 0-1000 with **y first**. ``box_2d: [ymin, xmin, ymax, xmax]`` (same scale, same
order) is read as its centre. Several points are scored at their centroid. A ``selected_image``
key in the same object names the frame.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.answers.text import coerce_index, coerce_numbers, find_objects, get_key
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading


class GeminiParser(NativeParser):
    """Gemini ``point: [y, x]`` / ``box_2d`` on 0-1000."""

    format_name = "Gemini point"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``point`` (or ``box_2d`` centre) in the text, in pixels."""
        reading = NativeReading()
        spans = []
        for obj in find_objects(text):
            _, point = get_key(obj.value, "point")
            _, box = get_key(obj.value, "box_2d")
            yx = coerce_numbers(point, 2)
            if yx is None and (b := coerce_numbers(box, 4)) is not None:
                yx = [(b[0] + b[2]) / 2, (b[1] + b[3]) / 2]
            if yx is None:
                continue
            reading.points.append(
                (relative_to_pixels(yx[1], 1000, spec.width), relative_to_pixels(yx[0], 1000, spec.height))
            )
            spans.append(obj.span)
            present, frame = get_key(obj.value, "selected_image")
            if present and coerce_index(frame) is not None:
                reading.selected_image = coerce_index(frame)
        reading.span = "\n".join(spans) or None
        return reading


@hookimpl
def register_parsers(register) -> None:
    """Contribute the gemini parser."""
    register("gemini", GeminiParser, description="Gemini point [y, x] / box_2d on 0-1000 (y first)")

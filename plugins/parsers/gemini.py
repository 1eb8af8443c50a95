"""The ``gemini`` parser: Gemini 2.x / Robotics-ER points, ``[{"point": [y, x], "label": ...}]``.

Coordinates are 0-1000 with **y first**. ``box_2d: [ymin, xmin, ymax, xmax]`` (same scale, same
order) is read as its centre. Several points are scored at their centroid. A ``selected_image``
key in the same object names the frame.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading, read_point_objects


class GeminiParser(NativeParser):
    """Gemini ``point: [y, x]`` / ``box_2d`` on 0-1000."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "Gemini's native format, `point: [y, x]` (or a `box_2d` centre) on 0-1000, else `json`"
    beside_official = 'adds: a native format the official runner does not read'

    format_name = "Gemini point"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``point`` (or ``box_2d`` centre) in the text, in pixels."""
        def yx_to_pixels(y: float, x: float) -> tuple[float, float]:  # y first
            return relative_to_pixels(x, 1000, spec.width), relative_to_pixels(y, 1000, spec.height)

        reading, spans = read_point_objects(text, "point", "box_2d", yx_to_pixels)
        reading.span = "\n".join(spans) or None
        return reading


@hookimpl
def register_parsers(register) -> None:
    """Contribute the gemini parser."""
    register("gemini", GeminiParser, description="Gemini point [y, x] / box_2d on 0-1000 (y first)")

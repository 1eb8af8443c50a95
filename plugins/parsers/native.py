"""What every native-format parser shares: points in a model's own format, else the asked JSON.

A native parser implements :meth:`NativeParser.read`, returning the points it found (already
converted to pixels of the requested size by the format's documented convention), the frame
they name if the format carries one, and the span they came from. Converting by a documented
convention is not a guess: such answers are ``ok`` (``repaired`` is for ``rescale-1000``).
Several points are scored at their centroid, all kept in ``points``. For A/B without an index in
the format, the frame is the one the text names (``selected_image: k`` or ``Image k``): a guess
from prose, so the answer is ``repaired`` and ``repair`` says so; else none (then unanswered, as
officially). When the text holds no native point at all, the model may have
followed the prompt: the ``json`` parser reads it, and the reason says so. Never raises.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass, field

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.answers.text import coerce_index, coerce_numbers, find_objects, get_key, mentioned_image
from povagent.answers.validation import judge_points
from povagent.interfaces import Parser
from povagent_plugins.parsers.json_answer import JsonAnswerParser, frame_from_text_repair


@dataclass
class NativeReading:
    """Points (pixels) read in a native format, the 0-based frame they name, the raw span."""

    points: list[tuple[float, float]] = field(default_factory=list)
    selected_image: int | None = None
    span: str | None = None
    note: str = ""


def read_point_objects(
    text: str, point_key: str, box_key: str, to_pixels: Callable[[float, float], tuple[float, float]]
) -> tuple[NativeReading, list[str]]:
    """The JSON objects of ``text`` that hold a point (``point_key: [a, b]``) or a box
    (``box_key: [a1, b1, a2, b2]``, read as its centre ``[a, b]``), as a reading and the spans
    they came from. ``to_pixels(a, b)`` turns the format's pair into pixels (its order and
    scale); a ``selected_image`` key in the same object names the frame (the last one wins)."""
    reading = NativeReading()
    spans: list[str] = []
    for obj in find_objects(text):
        _, point = get_key(obj.value, point_key)
        _, box = get_key(obj.value, box_key)
        pair = coerce_numbers(point, 2)
        if pair is None and (b := coerce_numbers(box, 4)) is not None:
            pair = [(b[0] + b[2]) / 2, (b[1] + b[3]) / 2]
        if pair is None:
            continue
        reading.points.append(to_pixels(pair[0], pair[1]))
        spans.append(obj.span)
        present, frame = get_key(obj.value, "selected_image")
        if present and coerce_index(frame) is not None:
            reading.selected_image = coerce_index(frame)
    return reading, spans


class NativeParser(Parser):
    """Base of the native-format parsers; subclasses set ``format_name`` and implement ``read``."""

    format_name = "native"

    @abc.abstractmethod
    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Points in this format, converted to pixels of ``spec``; ``None`` when there are none."""

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Native points if any (centroid, frame), else the asked JSON; never raises."""
        text = text or ""
        reading = self.read(text, spec) if text.strip() else None
        if reading is None or not reading.points:
            parsed = JsonAnswerParser().parse(text, spec)
            if not text.strip():
                return parsed
            note = f"nothing in the {self.format_name} format; read the asked JSON"
            return parsed.model_copy(update={"reason": f"{note}; {parsed.reason}" if parsed.reason else note})
        frame, repair = reading.selected_image, None
        if spec.asks_frame and frame is None:
            frame = mentioned_image(text)
            repair = frame_from_text_repair(frame) if frame is not None else None
        return judge_points(spec, reading.points, frame, span=reading.span, note=reading.note, repair=repair)

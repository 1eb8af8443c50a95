"""The ``robopoint`` parsers: RoboPoint's tuple lists, ``[(0.52, 0.31), (0.55, 0.33)]``.

Two modes, one per question a user asks:

* ``official`` (registered as ``robopoint-official``; the paper profile's parser) reads the answer
  exactly as the official runner reads RoboPoint (Given only): every ``(x, y)`` of two unsigned
  decimals (digits with at most one inner dot: ``0.5``, ``.5``, ``12``; not ``-0.1``, ``1.``,
  ``3e-1``) anywhere in the text, each multiplied by ``(W-1, H-1)`` whatever its magnitude (so
  ``(120, 300)`` is not read as pixels), all kept in ``points`` as the runner records them. The
  prediction is the point the official scorer scores: the centroid of the points after clamping
  each to the frame (``[0, W] x [0, H]``, i.e. ``[0, 1]`` once normalized); the closest point's
  error is kept by the scorer from ``points``. No tuple means no answer (no JSON fallback).
* ``lenient`` (``robopoint``, the default mode): signed numbers and a unicode minus are read, a
  tuple of two whole numbers is taken as pixels, fractions scale by ``W`` (``1.0`` maps to the
  last pixel), the centroid is taken before any clamping, and an answer without tuples is read
  as the asked JSON. A repair of the official reading: report it beside the official numbers.
"""

from __future__ import annotations

import math
import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable
from povagent.answers.text import NUMBER, normalize_minus
from povagent.answers.validation import judge, relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading

_TUPLE = re.compile(rf"\(\s*({NUMBER})\s*,\s*({NUMBER})\s*\)")
#: The official runner's tuple: unsigned decimals only.
_UNSIGNED = r"[0-9]*\.?[0-9]+"
_OFFICIAL_TUPLE = re.compile(rf"\(\s*({_UNSIGNED})\s*,\s*({_UNSIGNED})\s*\)")

MODES = ("lenient", "official")


def _is_whole(literal: str) -> bool:
    return "." not in literal


def official_points(text: str, spec: AnswerSpec) -> tuple[list[tuple[float, float]], list[str]]:
    """Every official RoboPoint tuple of ``text`` in pixels (fraction times ``W-1``, ``H-1``),
    with the literal tuples it came from."""
    points, spans = [], []
    for m in _OFFICIAL_TUPLE.finditer(text):
        points.append((float(m.group(1)) * (spec.width - 1), float(m.group(2)) * (spec.height - 1)))
        spans.append(m.group(0))
    return points, spans


def clamped_centroid(points: list[tuple[float, float]], width: int, height: int) -> tuple[float, float]:
    """The centroid of ``points`` after clamping each to ``[0, W] x [0, H]`` (the official scorer
    clamps each normalized point to ``[0, 1]`` before averaging)."""
    xs = [min(max(x, 0.0), float(width)) for x, _ in points]
    ys = [min(max(y, 0.0), float(height)) for _, y in points]
    return sum(xs) / len(xs), sum(ys) / len(ys)


def parse_official_robopoint(text: str, spec: AnswerSpec) -> ParsedAnswer:
    """RoboPoint's answer read as the official runner reads it (see the module docstring)."""
    points, spans = official_points(text or "", spec)
    if not points:
        return unparseable("no (x, y) tuple of unsigned decimals (the official RoboPoint reading)")
    # A number too long for a float reads as infinity: keep it on the frame's edge so the row
    # stays storable as JSON; the official scorer clamps it to the same edge.
    kept = [(x if math.isfinite(x) else float(spec.width), y if math.isfinite(y) else float(spec.height)) for x, y in points]
    cx, cy = clamped_centroid(kept, spec.width, spec.height)
    note = f"centroid of {len(kept)} point(s), each clamped to the frame first (official)"
    if spec.asks_frame:
        note += "; RoboPoint answers Given (C) only: officially it is never asked for a frame"
    parsed = judge(spec, cx, cy, None, span=", ".join(spans), points=kept, note=note)
    # every point is kept, a single one too, as the official runner records predicted_points
    return parsed.model_copy(update={"points": kept}) if parsed.answered else parsed


class RoboPointParser(NativeParser):
    """RoboPoint ``(x, y)`` tuples; option ``mode``: ``lenient`` (default) or ``official``."""

    format_name = "RoboPoint tuple"
    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "tuples with signs, integers as pixels, fractions times W, centroid before clamping, `json` when there is no tuple"
    beside_official = "adds: these variants, which `robopoint-official` does not read"

    def __init__(self, mode: str = "lenient") -> None:
        if mode not in MODES:
            raise ValueError(f"parser option mode must be one of {', '.join(MODES)}, got {mode!r}")
        self.mode = mode

    @property
    def reproduces_official(self) -> bool:
        """True in official mode: its numbers compare with the paper's."""
        return self.mode == "official"

    #: The parser whose reading is the official one for RoboPoint answers.
    official_reading = "robopoint-official"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """Every ``(x, y)`` tuple in the text, in pixels (lenient reading)."""
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

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Parse ``text`` in this parser's mode; never raises."""
        if self.mode == "official":
            return parse_official_robopoint(text, spec)
        return super().parse(text, spec)


class OfficialRoboPointParser(RoboPointParser):
    """The ``robopoint`` parser in its official mode (a name a model profile can give)."""

    reads = (
        "RoboPoint (Given only): every `(x, y)` of unsigned decimals, times (W-1, H-1) whatever the magnitude; "
        "each point clamped to the frame, then the centroid (closest point kept too)"
    )
    beside_official = "the reference for RoboPoint (the paper profile's parser)"

    def __init__(self) -> None:
        super().__init__(mode="official")


@hookimpl
def register_parsers(register) -> None:
    """Contribute the robopoint parsers."""
    register("robopoint", RoboPointParser, description="RoboPoint [(x, y), ...] fractions (integers: pixels); centroid; lenient (option mode: official)")
    register(
        "robopoint-official",
        OfficialRoboPointParser,
        description="RoboPoint tuples read as the official runner does (x (W-1), clamp each, centroid); paper-comparable",
    )

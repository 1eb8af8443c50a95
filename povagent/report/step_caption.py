"""How an active episode's step is written under its trajectory: ``move(forward=1.14, right=-0.47)``.

What it is for: a step's arguments are kept as the model sent them (JSON text, any length, any
precision). Cut at a fixed number of characters they mislead: ``"right": `` with the value
gone, ``"y": 255`` for 255.999. Here every number is rounded by one rule
(:func:`caption_number`), the arguments are written ``name=value`` in the order sent, and a
caption too long for its place is cut at the end with an ellipsis, never in silence. Arguments
that are no JSON object (a model's malformed call) are shown as sent, cut the same way.
What it must not do: read files, or change what the record holds.
"""

from __future__ import annotations

import json
import math
from typing import Any

#: Decimals every number of a caption is rounded to (centimetres and hundredths of a degree or a
#: pixel: finer than a trajectory drawing can show).
DECIMALS = 2
#: The longest caption of one step, in characters (the ellipsis included).
MAX_CAPTION = 60
#: The longest text argument shown (an ``ask`` question), in characters.
MAX_TEXT = 32
#: Where a caption or a text is cut.
ELLIPSIS = "\u2026"


def caption_number(value: float) -> str:
    """A number as captions write it: rounded to :data:`DECIMALS`, trailing zeros dropped
    (``255.999`` -> ``256``, ``-0.4656`` -> ``-0.47``, ``10.0`` -> ``10``)."""
    if not math.isfinite(value):
        return str(value)
    text = f"{value:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _value(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return json.dumps(v)
    if isinstance(v, float):
        return caption_number(v)
    if isinstance(v, int):
        return str(v) if abs(v) < 10**15 else caption_number(float(v))
    if isinstance(v, str):
        return json.dumps(shorten(v, MAX_TEXT), ensure_ascii=False)
    return shorten(json.dumps(v, ensure_ascii=False, separators=(",", ":")), MAX_TEXT)  # a nested value


def shorten(text: str, limit: int = MAX_CAPTION) -> str:
    """``text`` itself when it fits in ``limit`` characters, else cut with an ellipsis at the end."""
    return text if len(text) <= limit else text[: max(limit - 1, 0)] + ELLIPSIS


def step_caption(action: str, arguments: str, limit: int = MAX_CAPTION) -> str:
    """One step as ``action(name=value, ...)``: numbers rounded by :func:`caption_number`, long
    texts cut with an ellipsis, and arguments that do not fit in ``limit`` characters left out
    whole at the end (``, …)``), so no value is ever shown cut short without a mark."""
    try:
        parsed = json.loads(arguments, parse_constant=float)
    except (ValueError, RecursionError):
        parsed = None
    if not isinstance(parsed, dict):  # malformed arguments: as sent, cut
        return shorten(f"{action}({arguments})", limit)
    pieces = [f"{k}={_value(v)}" for k, v in parsed.items()]
    whole = f"{action}({', '.join(pieces)})"
    if len(whole) <= limit:
        return whole
    kept: list[str] = []
    for piece in pieces:
        if len(f"{action}({', '.join([*kept, piece])}, {ELLIPSIS})") > limit:
            break
        kept.append(piece)
    if not kept:
        return shorten(whole, limit)
    return f"{action}({', '.join(kept)}, {ELLIPSIS})"

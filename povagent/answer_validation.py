"""Judging a read answer against what was asked: the JSON Schema check and the parse status.

Every parser ends here: given pixel coordinates (and a frame for A/B) it validates them against
the strategy's answer schema with ``jsonschema`` and returns the typed :class:`ParsedAnswer`:

* ``ok``: valid against the schema (``repaired`` instead when the caller changed the numbers);
* ``out_of_range``: a point was read but the schema rejects it: a coordinate outside
  ``[0, W-1] x [0, H-1]`` (still an answer: the scorer clamps), or for A/B a selected frame that
  is missing or not among the frames shown (the official scorer then counts it unanswered);
* ``unparseable``: a coordinate that is not a finite number (``1e999`` read as infinity): no
  point can be scored from it, and it could not be written as JSON.

Validators are compiled once per distinct schema and cached (by object identity, falling back
to the schema's canonical JSON), so the hot path never recompiles. Pure: no I/O.
"""

from __future__ import annotations

import json
import math
import threading
from typing import Any, Sequence

from jsonschema import Draft202012Validator
from jsonschema.protocols import Validator

from povagent.answers import AnswerSpec, ParsedAnswer, ParseStatus, unparseable

_by_id: dict[int, tuple[dict[str, Any], Validator]] = {}
_by_text: dict[str, Validator] = {}
_lock = threading.Lock()
_MAX_CACHED = 1024


def validator_for(schema: dict[str, Any]) -> Validator:
    """The compiled validator of ``schema`` (compiled on first use, then cached)."""
    hit = _by_id.get(id(schema))
    if hit is not None and hit[0] is schema:
        return hit[1]
    text = json.dumps(schema, sort_keys=True, separators=(",", ":"))
    with _lock:
        validator = _by_text.get(text)
        if validator is None:
            Draft202012Validator.check_schema(schema)
            validator = Draft202012Validator(schema)
            if len(_by_text) >= _MAX_CACHED:
                _by_text.clear()
            _by_text[text] = validator
        if len(_by_id) >= _MAX_CACHED:
            _by_id.clear()
        # Holding the schema keeps its id from being reused while the entry lives.
        _by_id[id(schema)] = (schema, validator)
    return validator


def _describe(error: Any, answer: dict[str, Any]) -> str:
    """A short reason for one schema error, naming the field and its allowed range."""
    field = error.path[0] if error.path else None
    if error.validator == "required":
        missing = error.message.split("'")[1] if "'" in error.message else "a key"
        return f"{missing} missing"
    if field is not None:
        props = error.schema if isinstance(error.schema, dict) else {}
        lo, hi = props.get("minimum"), props.get("maximum")
        value = answer.get(field)
        if lo is not None and hi is not None:
            return f"{field}={value:g} outside [{lo:g}, {hi:g}]" if isinstance(value, (int, float)) else f"{field}={value!r} invalid"
        return f"{field}: {error.message}"
    return error.message


def judge(
    spec: AnswerSpec,
    x: float,
    y: float,
    selected_image: int | None = None,
    *,
    span: str | None = None,
    points: Sequence[tuple[float, float]] | None = None,
    repair: str | None = None,
    note: str = "",
) -> ParsedAnswer:
    """The typed parse of a point read from an answer (pixels of the requested frame size).

    ``selected_image`` is ignored for a point-only spec (C). ``repair`` (how the numbers were
    changed) turns a valid answer's status into ``repaired``. ``note`` is prefixed to the reason.
    """
    if not (math.isfinite(x) and math.isfinite(y)):
        reason = "; ".join(r for r in (note, f"coordinate not a finite number (x={x!r}, y={y!r})") if r)
        return unparseable(reason, span)
    answer: dict[str, Any] = {"x": x, "y": y}
    if spec.asks_frame and selected_image is not None:
        answer["selected_image"] = selected_image
    errors = sorted(validator_for(spec.json_schema).iter_errors(answer), key=lambda e: (list(e.path), e.validator))
    reasons = [_describe(e, answer) for e in errors]
    if errors:
        status = ParseStatus.OUT_OF_RANGE
    else:
        status = ParseStatus.REPAIRED if repair else ParseStatus.OK
    reason = "; ".join(r for r in [note, *(reasons or ([repair] if repair else []))] if r)
    return ParsedAnswer(
        status=status,
        reason=reason,
        selected_image=selected_image if spec.asks_frame else None,
        x=float(x),
        y=float(y),
        points=[(float(px), float(py)) for px, py in points] if points and len(points) > 1 else None,
        span=span,
        repair=repair,
    )


def judge_points(
    spec: AnswerSpec,
    points: Sequence[tuple[float, float]],
    selected_image: int | None = None,
    *,
    span: str | None = None,
    note: str = "",
    repair: str | None = None,
) -> ParsedAnswer:
    """The parse of one or more points (pixels): the centroid is the prediction, every point is
    kept in ``points`` (so a scorer can also report the closest one). ``repair`` as for :func:`judge`."""
    finite = [p for p in points if math.isfinite(p[0]) and math.isfinite(p[1])]
    if len(finite) < len(points):
        dropped = f"{len(points) - len(finite)} point(s) with a non-finite coordinate ignored"
        note = f"{note}; {dropped}" if note else dropped
        points = finite
    if not points:
        return unparseable(note or "no point in the answer", span)
    cx = sum(p[0] for p in points) / len(points)
    cy = sum(p[1] for p in points) / len(points)
    if len(points) > 1:
        note = "; ".join(r for r in (note, f"centroid of {len(points)} points") if r)
    return judge(spec, cx, cy, selected_image, span=span, points=points, note=note, repair=repair)


def relative_to_pixels(value: float, full_scale: float, size: int) -> float:
    """A coordinate on a ``[0, full_scale]`` convention (1000, 100, 1) in pixels of ``size``.

    ``value / full_scale * size``; a value on the convention's own range lands inside the frame
    (``full_scale`` itself maps to ``size - 1``, the last pixel), one outside it stays outside.
    """
    px = value / full_scale * size
    if 0 <= value <= full_scale:
        px = min(px, size - 1)
    return px

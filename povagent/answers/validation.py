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
to the schema's canonical JSON), so the hot path never recompiles. For the usual answer schemas
(an object of required numbers and integers with inclusive bounds, as
:func:`povagent.answers.spec.frame_answer_schema` makes) a compiled pre-check recognises a valid
answer without walking jsonschema's keyword machinery; anything it cannot vouch for (an error,
a float where an integer is asked, a schema of another shape) goes to ``jsonschema``, which
stays the authority for every error and its message. Pure: no I/O.
"""

from __future__ import annotations

import json
import math
import threading
from typing import Any, Callable, Sequence

from jsonschema import Draft202012Validator
from jsonschema.protocols import Validator

from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable

#: A pre-check: ``answer -> True`` when the answer is certainly valid against its schema
#: (``False`` means "ask jsonschema", not "invalid").
PreCheck = Callable[[dict[str, Any]], bool]

_by_id: dict[int, tuple[dict[str, Any], Validator, PreCheck | None]] = {}
_by_text: dict[str, tuple[Validator, PreCheck | None]] = {}
_lock = threading.Lock()
_MAX_CACHED = 1024

#: Keywords that never make an instance invalid (annotations).
_ANNOTATIONS = frozenset({"title", "description", "$comment", "examples", "default"})


def _bound(value: Any) -> bool:
    return type(value) in (int, float) and math.isfinite(value)


def compile_precheck(schema: dict[str, Any]) -> PreCheck | None:
    """A fast check that recognises answers valid against ``schema``, or ``None`` when the
    schema is not of the shape it understands.

    Understood: ``{"type": "object", "required": [...], "properties": {name: {"type":
    "number" | "integer", "minimum": m, "maximum": M}}}`` (each keyword optional, annotations
    allowed). The check answers ``True`` only when every required key is present and every
    present property is an ``int`` (or, for ``number``, a ``float``; never a ``bool``) inside
    its inclusive bounds: exactly the cases in which jsonschema reports no error. Anything
    else answers ``False`` and the caller asks jsonschema (which then words the errors).
    """
    if not isinstance(schema, dict) or set(schema) - {"type", "required", "properties"} - _ANNOTATIONS:
        return None
    if schema.get("type", "object") != "object":
        return None
    required = schema.get("required", [])
    properties = schema.get("properties", {})
    if not isinstance(required, list) or not all(isinstance(k, str) for k in required):
        return None
    if not isinstance(properties, dict):
        return None
    checks: list[tuple[str, tuple[type, ...], float | None, float | None]] = []
    for name, sub in properties.items():
        if not isinstance(name, str) or not isinstance(sub, dict) or set(sub) - {"type", "minimum", "maximum"} - _ANNOTATIONS:
            return None
        kind = sub.get("type")
        if kind == "number":
            types: tuple[type, ...] = (int, float)
        elif kind == "integer":
            types = (int,)  # an integral float is valid too, but rare: jsonschema decides it
        else:
            return None
        lo, hi = sub.get("minimum"), sub.get("maximum")
        if (lo is not None and not _bound(lo)) or (hi is not None and not _bound(hi)):
            return None
        checks.append((name, types, lo, hi))
    required_keys = tuple(required)
    frozen = tuple(checks)

    def precheck(answer: dict[str, Any]) -> bool:
        for key in required_keys:
            if key not in answer:
                return False
        for name, types, lo, hi in frozen:
            if name in answer:
                value = answer[name]
                if type(value) not in types:  # exact types: bool (an int subclass) is never a number
                    return False
                # ``not (lo <= value)`` also sends NaN to jsonschema
                if (lo is not None and not lo <= value) or (hi is not None and not value <= hi):
                    return False
        return True

    return precheck


def _compiled(schema: dict[str, Any]) -> tuple[Validator, PreCheck | None]:
    """The validator and pre-check of ``schema`` (compiled on first use, then cached)."""
    hit = _by_id.get(id(schema))
    if hit is not None and hit[0] is schema:
        return hit[1], hit[2]
    text = json.dumps(schema, sort_keys=True, separators=(",", ":"))
    with _lock:
        entry = _by_text.get(text)
        if entry is None:
            Draft202012Validator.check_schema(schema)
            entry = (Draft202012Validator(schema), compile_precheck(schema))
            if len(_by_text) >= _MAX_CACHED:
                _by_text.clear()
            _by_text[text] = entry
        if len(_by_id) >= _MAX_CACHED:
            _by_id.clear()
        # Holding the schema keeps its id from being reused while the entry lives.
        _by_id[id(schema)] = (schema, *entry)
    return entry


def validator_for(schema: dict[str, Any]) -> Validator:
    """The compiled validator of ``schema`` (compiled on first use, then cached)."""
    return _compiled(schema)[0]


def schema_errors(schema: dict[str, Any], answer: dict[str, Any]) -> list[Any]:
    """jsonschema's errors for ``answer``, sorted by path then keyword (empty when valid).

    The pre-check answers the common valid case; jsonschema is asked otherwise.
    """
    validator, precheck = _compiled(schema)
    if precheck is not None and precheck(answer):
        return []
    return sorted(validator.iter_errors(answer), key=lambda e: (list(e.path), e.validator))


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
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                return f"{field}={shown_number(value)} outside [{lo:g}, {hi:g}]"
            return f"{field}={value!r} invalid"
        return f"{field}: {error.message}"
    return error.message


def shown_number(value: float) -> str:
    """A number of an answer, short enough for a reason: an integer too long to read (a 400-digit
    frame index; no float holds it, and past 4,300 digits Python will not print it) is named by
    its length, never converted."""
    if isinstance(value, int) and abs(value) >= 10**15:
        magnitude = abs(value)
        digits = int(math.log10(magnitude)) + 1  # a float's estimate, exact after the correction
        digits += (magnitude >= 10**digits) - (magnitude < 10 ** (digits - 1))
        return f"{'a negative ' if value < 0 else 'a '}{digits}-digit integer"
    return f"{value:g}"


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
    errors = schema_errors(spec.json_schema, answer)
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

"""The ``official`` parser: an answer read exactly as the official runner reads it.

The official runner (``mimo-owl/povbench-eval``, ``evaluation/run_vlm_eval.py``) defines which
answers count; this parser reproduces its reading, so that numbers parsed with it compare with the
paper's. Nothing is repaired:

* **Objects.** Every ``{...}`` that holds no brace inside it, in text order, read by Python's
  ``json.loads``: ``NaN``, ``Infinity`` and ``1e999`` (infinity) are accepted; trailing commas,
  single quotes, comments, bare keys, ``+1`` or ``1.`` are not (that object is skipped). An object
  with an object inside it is never read itself (only the inner one is).
* **Choice.** Among the objects carrying the asked keys (exact case: ``selected_image``, ``x``,
  ``y`` for A/B; ``x``, ``y`` for C) whose ``x`` and ``y`` convert with ``float()``: the last one
  inside ``[0, W-1] x [0, H-1]``, else the last one. ``float()`` takes what Python's does:
  ``true`` -> 1.0, ``"1_20"`` -> 120.0, ``"nan"``; not ``"120px"``, ``null`` or a list.
* **Frame.** ``int(selected_image)`` of the chosen object: ``3.6`` -> 3, ``"3"`` -> 3,
  ``true`` -> 1, ``-0.5`` -> 0; ``"3.0"``, ``"image_3"``, ``null`` leave the row unanswered, even
  when an earlier object had a usable frame. An index outside the frames shown is kept (status
  ``out_of_range``): the official runner then records no ``predicted_image`` and its scorer counts
  the row unanswered, as ours does.
* **Aborts.** Where the official parse raises instead of returning (an integer too large for a
  float, ``int(inf)``, arrays nested past Python's recursion limit), the runner records the error
  and no answer: so does this parser.
* **Non-finite coordinates** are kept as the runner records them: infinity (status
  ``out_of_range``; the official scorer clamps it to the image edge) and NaN (the official scorer
  counts the row answered with a NaN error, which makes every mean holding it NaN: the reason
  says so, and the rescore command names such rows in a warning).

The range that decides the choice is the one asked (the strategy's ``W x H``): the official
runner checks 512 x 512 whatever the camera, which is the same on the release (every frame is
512 x 512). Pure, never raises.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.answers.validation import judge
from povagent.interfaces import Parser

#: A brace group with no brace inside it (what the official runner looks for).
_FLAT_OBJECT = re.compile(r"\{[^{}]*\}")


class OfficialParseAborted(Exception):
    """The official parse would raise here (its runner then records no answer)."""


@dataclass(frozen=True)
class FlatObject:
    """One flat ``{...}`` that ``json.loads`` accepts, and its text."""

    value: dict[str, Any]
    span: str


def flat_objects(text: str) -> list[FlatObject]:
    """Every flat ``{...}`` of ``text`` that ``json.loads`` reads, in text order."""
    found = []
    for match in _FLAT_OBJECT.finditer(text.strip()):
        try:
            value = json.loads(match.group())
        except ValueError:  # not JSON, or an integer of more than 4,300 digits: skipped
            continue
        except RecursionError as exc:  # escapes the official parse: the row has no answer
            raise OfficialParseAborted(f"json.loads raised RecursionError on {match.group()[:40]!r}...") from exc
        found.append(FlatObject(value, match.group()))
    return found


def as_float(value: Any) -> float | None:
    """``float(value)``, or ``None`` where the official choice skips the object."""
    try:
        return float(value)
    except (ValueError, TypeError):
        return None
    except OverflowError as exc:  # not caught by the official choice: the parse aborts
        raise OfficialParseAborted(f"float() raised OverflowError: {exc}") from exc


@dataclass(frozen=True)
class Chosen:
    """The object the official choice takes, with its coordinates as ``float()`` read them."""

    obj: FlatObject
    x: float
    y: float


def choose_official(objects: list[FlatObject], keys: tuple[str, ...], width: int, height: int) -> Chosen | None:
    """The last object with ``keys`` whose point converts and lies in ``[0, W-1] x [0, H-1]``,
    else the last one with ``keys`` whose point converts; ``None`` when there is none."""
    last_converting: Chosen | None = None
    for obj in reversed(objects):
        if not all(k in obj.value for k in keys):
            continue
        x = as_float(obj.value["x"])
        if x is None:
            continue
        y = as_float(obj.value["y"])
        if y is None:
            continue
        chosen = Chosen(obj, x, y)
        if last_converting is None:
            last_converting = chosen
        if 0 <= x <= width - 1 and 0 <= y <= height - 1:
            return chosen
    return last_converting


def frame_index(value: Any) -> int | None:
    """``int(value)`` as the official runner takes the selected frame; ``None`` when it fails."""
    try:
        return int(value)
    except (ValueError, TypeError):
        return None
    except OverflowError as exc:  # int(inf): escapes the official parse
        raise OfficialParseAborted(f"int() raised OverflowError: {exc}") from exc


def non_finite_answer(spec: AnswerSpec, x: float, y: float, frame: int | None, span: str) -> ParsedAnswer:
    """An answer with an infinite or NaN coordinate, kept as the official runner records it."""
    if math.isnan(x) or math.isnan(y):
        why = (
            f"x={x!r}, y={y!r}: the official runner records NaN and its scorer counts the row "
            "answered with a NaN error, so every mean holding this row is NaN"
        )
    else:
        why = f"x={x!r}, y={y!r}: infinite, scored at the image edge as the official scorer clamps it"
    return ParsedAnswer(
        status=ParseStatus.OUT_OF_RANGE,
        reason=why,
        selected_image=frame if spec.asks_frame else None,
        x=x,
        y=y,
        span=span,
    )


def parse_official(text: str, spec: AnswerSpec) -> ParsedAnswer:
    """The answer in ``text`` as the official runner reads it (see the module docstring)."""
    keys = ("selected_image", "x", "y") if spec.asks_frame else ("x", "y")
    try:
        objects = flat_objects(text or "")
        chosen = choose_official(objects, keys, spec.width, spec.height)
        if chosen is None:
            if not objects:
                return unparseable("no flat JSON object that json.loads reads")
            return unparseable(f"no JSON object with the keys {', '.join(keys)} and numbers x, y", objects[-1].span)
        frame = None
        if spec.asks_frame:
            raw_frame = chosen.obj.value["selected_image"]
            frame = frame_index(raw_frame)
            if frame is None:
                return unparseable(f"selected_image {raw_frame!r} of the chosen object is not an integer", chosen.obj.span)
    except OfficialParseAborted as exc:
        return unparseable(f"the official parse raises here ({exc}); its runner records no answer")
    if not (math.isfinite(chosen.x) and math.isfinite(chosen.y)):
        return non_finite_answer(spec, chosen.x, chosen.y, frame, chosen.obj.span)
    return judge(spec, chosen.x, chosen.y, frame, span=chosen.obj.span)


class OfficialParser(Parser):
    """The official runner's reading of the asked JSON answer, nothing repaired."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = ("every flat `{...}` (no brace inside) that `json.loads` accepts; keys `selected_image`, `x`, `y` (C: `x`, `y`), exact case; the last object whose "
             "`float(x)`, `float(y)` lie in [0, W-1] x [0, H-1], else the last that converts; then `int(selected_image)`")
    beside_official = ('the reference: `NaN`/`Infinity`/`1e999` kept (infinity is scored at the edge, NaN makes the official mean NaN and is named in a '
                       'warning); `3.6` -> frame 3, `"3"` -> 3, `true` -> 1 (coordinates too); trailing commas, single quotes, comments, upper-case keys, '
                       '`"120px"`, a nested extra field, `"image_3"`, `null` frame: unanswered')

    #: Numbers read by this parser compare with the paper's (see
    #: :func:`povagent.results.official_reading.official_counterpart`).
    reproduces_official = True
    #: The parse depends on the reply and the asked spec alone (see :class:`~povagent_plugins.parsers.mcq.rule.RuleParser`).
    reads_text_alone = True

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Parse ``text`` as the official runner does; never raises."""
        return parse_official(text, spec)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the official parser."""
    register(
        "official",
        OfficialParser,
        description="The official runner's reading exactly (flat {...}, json.loads, last in range else last); paper-comparable",
    )

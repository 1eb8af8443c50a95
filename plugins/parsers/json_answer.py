"""The ``json`` parser: the answer format the paper's prompts ask for, read as the official code does.

The choice is the official one: among the objects with the requested keys, the last whose
``x`` and ``y`` lie in ``[0, W-1] x [0, H-1]``, else the last (this catches self-corrections after
chain-of-thought); the frame is then the chosen object's, and when it is missing or no frame
index the row has no frame (unanswered, as officially), never an earlier object's. The reading
is lenient, which the official runner's is not (see the ``official`` parser for the exact one):
it also reads objects nested in others, trailing commas, single quotes, comments, bare keys,
case-insensitive keys, numbers as strings with ``px``, a unicode minus, and frames written
``"Image 3"``; it refuses booleans and non-finite numbers as coordinates (see
:mod:`povagent.answers.text`). Numbers parsed with it are repairs: report them beside the
official parse's.

For A/B, when no object carries ``selected_image`` but one carries ``x`` and ``y``, the official
reading has no answer. This parser returns that point with the frame the text names
(``selected_image: k`` or the last ``Image k``) as a *repair* (status ``repaired``, ``repair``
saying so, so that reports can tell it from an answer the official parser would accept), or with
no frame (status ``out_of_range``, which the scorer counts as unanswered). Never raises.
"""

from __future__ import annotations

from dataclasses import dataclass

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable
from povagent.answers.text import JsonObject, coerce_index, coerce_number, find_objects, get_key, mentioned_image
from povagent.answers.validation import judge
from povagent.interfaces import Parser


@dataclass(frozen=True)
class Candidate:
    """An object that holds a point: its raw numbers as written and where it came from."""

    x: float
    y: float
    selected_image: int | None
    has_frame_key: bool
    source: JsonObject


def read_candidate(obj: JsonObject) -> Candidate | None:
    """The point an object holds (numeric ``x`` and ``y``), or ``None``."""
    has_x, x = get_key(obj.value, "x")
    has_y, y = get_key(obj.value, "y")
    if not (has_x and has_y):
        return None
    fx, fy = coerce_number(x), coerce_number(y)
    if fx is None or fy is None:
        return None
    has_frame, frame = get_key(obj.value, "selected_image")
    return Candidate(fx, fy, coerce_index(frame) if has_frame else None, has_frame, obj)


def candidates(text: str, spec: AnswerSpec, objects: list[JsonObject] | None = None) -> tuple[list[Candidate], bool]:
    """Objects with the requested keys, in text order; the flag says whether they lack the
    frame key (A/B objects with only ``x`` and ``y``, used when nothing better exists).
    ``objects`` is ``find_objects(text)`` when the caller already has it."""
    objects = find_objects(text) if objects is None else objects
    read = [c for c in (read_candidate(o) for o in objects) if c is not None]
    if not spec.asks_frame:
        return read, False
    full = [c for c in read if c.has_frame_key]
    return (full, False) if full else (read, True)


def frame_from_text_repair(frame: int) -> str:
    """The ``repair`` of an answer whose frame was read from its prose, not from its JSON."""
    return f"selected_image {frame} taken from the text"


def judge_candidate(cand: Candidate, spec: AnswerSpec, text: str, frame_from_text: bool) -> ParsedAnswer:
    """The typed parse of one candidate (frame from the text, as a repair, when the object has none)."""
    frame = cand.selected_image
    note, repair = "", None
    if spec.asks_frame and frame_from_text:
        frame = mentioned_image(text)
        if frame is None:
            note = "no selected_image key, and the text names no frame"
        else:
            note, repair = "no selected_image key", frame_from_text_repair(frame)
    elif spec.asks_frame and frame is None:
        note = f"selected_image {get_key(cand.source.value, 'selected_image')[1]!r} is not a frame index"
    return judge(spec, cand.x, cand.y, frame, span=cand.source.span, note=note, repair=repair)


def choose(text: str, spec: AnswerSpec, objects: list[JsonObject] | None = None) -> tuple[Candidate | None, ParsedAnswer]:
    """The official choice over the candidates read: the last whose point is in range, else the
    last; its frame is judged as it is. ``objects`` is ``find_objects(text)`` when the caller
    already has it."""
    if not text or not text.strip():
        return None, unparseable("empty answer")
    objects = find_objects(text) if objects is None else objects
    found, frame_from_text = candidates(text, spec, objects)
    if not found:
        keys = ", ".join(spec.required_keys)
        if not objects:
            return None, unparseable("no readable JSON object in the answer")
        return None, unparseable(f"no JSON object with numeric {keys}", objects[-1].span)
    # As officially, only the point decides: a chosen object whose frame is missing, not an
    # index or not among the frames shown leaves the row without a frame (unanswered); it never
    # sends the choice back to an earlier object.
    chosen = next((c for c in reversed(found) if point_in_frame(c, spec)), found[-1])
    return chosen, judge_candidate(chosen, spec, text, frame_from_text)


def point_in_frame(cand: Candidate, spec: AnswerSpec) -> bool:
    """Whether a candidate's point lies in ``[0, W-1] x [0, H-1]`` (the official preference)."""
    return 0 <= cand.x <= spec.width - 1 and 0 <= cand.y <= spec.height - 1


class JsonAnswerParser(Parser):
    """The official JSON reading, tolerant of real-world formatting."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "the same choice (last in range, else last; the chosen object's frame decides) over a lenient reading"
    beside_official = ('adds: trailing commas, single quotes, `//` and `/* */` comments, bare and upper-case keys, Python `True/None`, unicode minus, `+1`, '
                       '`1.`, `"120px"`, objects nested in others, frames written `"Image 3"`, the frame named in the prose when the object has none (status '
                       '`repaired`); refuses boolean and non-finite coordinates')

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Parse ``text`` (see the module docstring); never raises."""
        return choose(text or "", spec)[1]


@hookimpl
def register_parsers(register) -> None:
    """Contribute the json parser."""
    register("json", JsonAnswerParser, description="Requested JSON answer, lenient reading (repairs), official choice (last in range, else last)")

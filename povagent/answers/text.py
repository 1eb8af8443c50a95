"""Reading answer-like pieces out of a model's free text: JSON objects, numbers, frame mentions.

Real answers wrap the requested JSON in markdown fences and prose, write numbers as strings,
leave trailing commas, use single quotes, bare keys, Python literals or a unicode minus.
:func:`find_objects` finds every balanced ``{...}`` in the text (at any nesting depth, ordered
by where they end, as "last" means for the official parser) and reads each leniently. Pure
functions over strings, shared by the built-in parsers and open to third-party ones; nothing
here knows what was asked (see :mod:`povagent.answers.validation` for that).

What is deliberately *not* done: an object cut off before its closing brace (a truncated
answer) is not completed, because its last number may itself be cut (``"y": 31`` of ``310``).

Hostile text must cost little: a ``{...}`` holding more than :data:`MAX_NESTING` levels of
braces is not read itself (the objects inside it still are), so deep nesting costs linear time,
not quadratic; digit runs too long for ``int`` read as "no number", never as an exception.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any

#: Characters models write for a minus sign besides ``-`` (minus, figure dash, en dash,
#: small and full-width hyphen-minus): only replaced directly before a digit.
_MINUS_LIKE = "\u2212\u2012\u2013\ufe63\uff0d"
_MINUS_BEFORE_DIGIT = re.compile(f"[{_MINUS_LIKE}](?=\\s*\\d)")
_SMART_DOUBLE = re.compile("[\u201c\u201d\u201e\u201f\u2033]")
_SMART_SINGLE = re.compile("[\u2018\u2019\u201a\u201b\u2032]")
_TRAILING_COMMA = re.compile(r",\s*([}\]])")
_BARE_KEY = re.compile(r"([{,]\s*)([A-Za-z_][A-Za-z0-9_]*)(\s*:)")
_SINGLE_QUOTED = re.compile(r"'((?:[^'\\\n]|\\.)*)'")
#: A single-quoted string where JSON allows one (after ``{ [ , :``, before ``: , } ]``), with
#: any apostrophe inside it kept ('robot's chair'). Each match is bounded, and the pattern is
#: only tried on short objects, so hostile text cannot make it slow.
_SINGLE_QUOTED_WITH_APOSTROPHES = re.compile(r"(?<=[{\[,:])(\s*)'((?:[^'\\\n]|\\.|'(?!\s*[:,}\]])){0,200})'(?=\s*[:,}\]])")
_APOSTROPHE_OBJECT_MAX = 2000
_LINE_COMMENT = re.compile(r"(?<![:\w])//[^\n]*")
_TRAILING_DOT = re.compile(r"(?<=\d)\.(?=\s*[,}\]])")
_PY_LITERALS = re.compile(r"(?<![\"\w])(None|True|False)(?![\"\w])")
_PLUS_NUMBER = re.compile(r"(:\s*)\+(?=\d)")
_NUMBER_TEXT = re.compile(r"^[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?$")
_INDEX_TEXT = re.compile(r"^(?:image|frame|img)?\s*[_#:]?\s*(\d+)$", re.IGNORECASE)
_SELECTED_KEY = re.compile(r"""["']?selected_image["']?\s*[:=]\s*["']?(\d+)""", re.IGNORECASE)
_IMAGE_MENTION = re.compile(r"\bimage\s*(?:#|no\.?|number|index)?\s*(\d+)\b", re.IGNORECASE)
_FENCE_LINE = re.compile(r"^\s*(```|~~~)[\w-]*\s*$")

#: A number as models write it (unicode minus allowed), for regex-based native formats.
NUMBER = rf"[+\-{_MINUS_LIKE}]?(?:\d+(?:\.\d*)?|\.\d+)"

#: Braces nested deeper than this inside one ``{...}``: that object is not read (an answer
#: object nests two or three levels; only garbage nests deeper, and reading every level of it
#: would cost time quadratic in its length).
MAX_NESTING = 16

#: Longest digit run read as a frame index (a longer one is no index: it could not name a
#: frame shown, and ``int`` refuses runs past 4,300 digits).
_MAX_INDEX_DIGITS = 9


@dataclass(frozen=True)
class JsonObject:
    """A ``{...}`` read from the text: its value, and where it was (``text[start:end]`` is ``span``)."""

    value: dict[str, Any]
    start: int
    end: int
    span: str


def normalize_minus(text: str) -> str:
    """``text`` with minus-like characters before digits turned into ``-``."""
    return _MINUS_BEFORE_DIGIT.sub("-", text)


def _without_block_comments(text: str) -> str:
    """``text`` without ``/* ... */`` comments (scanned with ``find``: linear on any input)."""
    kept, i = [], 0
    while (start := text.find("/*", i)) >= 0 and (end := text.find("*/", start + 2)) >= 0:
        kept.append(text[i:start])
        i = end + 2
    kept.append(text[i:])
    return "".join(kept)


def lenient_json(candidate: str) -> Any:
    """Parse one JSON value the way a forgiving reader would; ``None`` when it cannot.

    Strict JSON first; then curly quotes to straight, unicode minus to ``-``, ``//`` and
    ``/* */`` comments removed, Python ``None/True/False``, a leading ``+`` and a trailing dot
    (``20.``) on numbers and trailing commas removed, bare keys quoted; and only if that still
    fails, single-quoted strings turned double-quoted.
    """
    try:
        return json.loads(candidate)
    except (ValueError, RecursionError):  # JSONDecodeError, or an integer of > 4,300 digits
        pass
    s = _SMART_DOUBLE.sub('"', candidate)
    s = _SMART_SINGLE.sub("'", s)
    s = normalize_minus(s)
    s = _LINE_COMMENT.sub("", _without_block_comments(s))
    s = _TRAILING_DOT.sub("", s)
    s = _PY_LITERALS.sub(lambda m: {"None": "null", "True": "true", "False": "false"}[m.group(1)], s)
    s = _PLUS_NUMBER.sub(r"\1", s)
    s = _TRAILING_COMMA.sub(r"\1", s)
    # Single quotes last and only if needed: an apostrophe inside a double-quoted label
    # ("robot's chair") must survive when the object was fine apart from, say, a comma.
    attempts = [s]
    if "'" in s:
        attempts.append(_SINGLE_QUOTED.sub(lambda m: json.dumps(m.group(1).replace("\\'", "'")), s))
        if len(s) <= _APOSTROPHE_OBJECT_MAX:
            attempts.append(
                _SINGLE_QUOTED_WITH_APOSTROPHES.sub(lambda m: m.group(1) + json.dumps(m.group(2).replace("\\'", "'")), s)
            )
    for attempt in attempts:
        attempt = _BARE_KEY.sub(lambda m: f'{m.group(1)}"{m.group(2)}"{m.group(3)}', attempt)
        try:
            return json.loads(attempt)
        except (ValueError, RecursionError):
            continue
    return None


def find_objects(text: str) -> list[JsonObject]:
    """Every balanced ``{...}`` of ``text`` that reads as a JSON object, ordered by its end.

    Nested objects are found too (the inner one ends first). Braces are matched without
    regard to strings: answers rarely put braces inside strings, and tracking quotes would
    let a prose apostrophe ("robot's") derail the scan. An object holding more than
    :data:`MAX_NESTING` levels of braces is skipped (its inner objects are still read).
    """
    found: list[JsonObject] = []
    # each open brace: [offset, deepest nesting seen inside it so far]
    stack: list[list[int]] = []
    for i, ch in enumerate(text):
        if ch == "{":
            stack.append([i, 0])
        elif ch == "}" and stack:
            start, depth = stack.pop()
            if stack and stack[-1][1] < depth + 1:
                stack[-1][1] = depth + 1
            span = text[start : i + 1]
            # an object with a key has a ":": "{}" and prose in braces are skipped unparsed
            if depth > MAX_NESTING or ":" not in span:
                continue
            value = lenient_json(span)
            if isinstance(value, dict):
                found.append(JsonObject(value, start, i + 1, span))
    return found


def index_from_digits(digits: str) -> int | None:
    """A frame index from a run of decimal digits (what ``\\d`` matches); ``None`` for anything
    else (``"²"`` is a digit to ``str.isdigit`` but not to ``int``) or an absurdly long run (no
    frame shown has such an index, and ``int`` refuses one of over 4,300 digits)."""
    if not digits.isdecimal() or len(digits.lstrip("0")) > _MAX_INDEX_DIGITS:
        return None
    return int(digits)


def get_key(obj: dict[str, Any], key: str) -> tuple[bool, Any]:
    """``(present, value)`` for ``key`` in ``obj``, matching case-insensitively if not exact."""
    if key in obj:
        return True, obj[key]
    lowered = key.lower()
    for k, v in obj.items():
        if isinstance(k, str) and k.strip().lower() == lowered:
            return True, v
    return False, None


def coerce_number(value: Any) -> float | None:
    """A finite number from a JSON value: numbers, numeric strings (``"212"``, ``"−3.5"``,
    ``"212px"``); ``None`` for anything else (booleans, NaN, lists, words)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, int):
        try:
            return float(value)
        except OverflowError:  # an integer past a float's range (a 400-digit literal): no finite number
            return None
    if isinstance(value, str):
        s = normalize_minus(value.strip())
        if s.lower().endswith("px"):
            s = s[:-2].strip()
        if _NUMBER_TEXT.match(s):
            f = float(s)
            return f if math.isfinite(f) else None
    return None


def coerce_index(value: Any) -> int | None:
    """A frame index from a JSON value: ``3``, ``3.0``, ``"3"``, ``"Image 3"``; else ``None``."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return int(value) if value.is_integer() else None
    if isinstance(value, str):
        m = _INDEX_TEXT.match(value.strip())
        if m:
            return index_from_digits(m.group(1))
        f = coerce_number(value)
        if f is not None and f.is_integer():
            return int(f)
    return None


def mentioned_image(text: str) -> int | None:
    """The frame an answer names outside a usable JSON object: the last ``selected_image: k``,
    else the last ``Image k`` mention; ``None`` when there is neither."""
    keyed = list(_SELECTED_KEY.finditer(text))
    if keyed:
        return index_from_digits(keyed[-1].group(1))
    mentions = list(_IMAGE_MENTION.finditer(text))
    if mentions:
        return index_from_digits(mentions[-1].group(1))
    return None


def final_line_start(text: str) -> int:
    """Offset where the answer's last line starts (trailing blank and code-fence lines skipped)."""
    end = len(text)
    while True:
        line_start = text.rfind("\n", 0, end) + 1
        line = text[line_start:end]
        if line.strip() and not _FENCE_LINE.match(line):
            return line_start
        if line_start == 0:
            return 0
        end = line_start - 1


def coerce_numbers(value: Any, n: int) -> list[float] | None:
    """A list of exactly ``n`` numbers (each as :func:`coerce_number` reads it), else ``None``."""
    if not isinstance(value, (list, tuple)) or len(value) != n:
        return None
    numbers = [coerce_number(v) for v in value]
    read = [v for v in numbers if v is not None]
    return read if len(read) == n else None

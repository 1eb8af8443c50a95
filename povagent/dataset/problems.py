"""Problems found in a dataset: file, JSON path and a plain sentence.

Shared by loading (which reports a bad house and goes on) and ``povagent validate`` (which
reports every problem). Converts pydantic and jsonschema errors into readable sentences, and
holds the rules every value read from a dataset's JSON obeys: numbers are finite, and text is
text (:func:`not_text_problems`).
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any, Iterable, Iterator

from pydantic import ValidationError


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a dataset file."""

    file: str
    json_path: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}: {self.json_path}" if self.json_path and self.json_path != "$" else self.file
        return f"{where}: {self.message}"


def json_path(loc: Iterable[Any]) -> str:
    """``('stage3', 'left', 'verdict')`` -> ``$.stage3.left.verdict``; ints become ``[i]``."""
    out = "$"
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part == "[key]":
            continue  # pydantic marks a bad dict key by appending "[key]" after it
        else:
            out += f".{part}"
    return out


def non_finite_numbers(data: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[tuple[Any, ...], float]]:
    """``(location, value)`` of every NaN or infinity in parsed JSON, in document order.

    Python's ``json`` reads ``NaN``, ``Infinity`` and overflowing literals (``1e999``) as
    floats; no release field may hold one. Walks without recursion: a hostile file may nest
    deeply. A location is made only for a number found (every record of a release is checked as
    it is loaded: a location made for every number was most of a release's loading).
    """
    if isinstance(data, float):
        if not math.isfinite(data):
            yield prefix, data
        return
    if not isinstance(data, (dict, list)):
        return
    # each level gone into: its key in the level above and what is left of its items, in order
    # (depth first); a location is put together from the keys only for a number found
    stack: list[tuple[Any, Iterator[tuple[Any, Any]]]] = [(None, _items(data))]
    while stack:
        for key, value in stack[-1][1]:
            if isinstance(value, float):
                if not math.isfinite(value):
                    yield prefix + tuple(k for k, _ in stack[1:]) + (key,), value
            elif isinstance(value, (dict, list)):
                stack.append((key, _items(value)))
                break
        else:
            stack.pop()


def _items(container: dict[Any, Any] | list[Any]) -> Iterator[tuple[Any, Any]]:
    return iter(list(container.items())) if isinstance(container, dict) else enumerate(list(container))


def non_finite_message(value: float) -> str:
    """The sentence for a non-finite number."""
    return f"is {value!r}, not a finite number (NaN and Infinity are not positions, angles or sizes)"


def non_finite_problems(file: str, data: Any, prefix: tuple[Any, ...] = ()) -> list[Problem]:
    """One :class:`Problem` per NaN or infinity in ``data``."""
    return [Problem(file, json_path(loc), non_finite_message(v)) for loc, v in non_finite_numbers(data, prefix)]


#: A UTF-16 surrogate code point. Python's ``json`` joins an escaped pair (``\\ud83d\\ude00``)
#: into one character, so any surrogate left in a parsed string is a lone one.
_SURROGATE = re.compile("[\ud800-\udfff]")


def _escaped(text: str) -> str:
    """``text`` with lone surrogates written as ``\\udXXX`` (a message can always be printed)."""
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def not_text_problems(file: str, data: Any) -> list[Problem]:
    """One :class:`Problem` per string (value or key) of parsed JSON holding a lone surrogate.

    JSON may write ``"\\ud800"``, and Python's ``json`` reads it as a string no UTF-8 file can
    hold: every result row, prompt, report and export holding it would fail to be written. So
    a dataset file holding one is not text, as a file with a byte that is not UTF-8 is not:
    loading refuses the file and ``validate`` names each string by file and JSON path. Walks
    without recursion (a hostile file may nest deeply); paths show bad keys escaped.
    """
    if all_text(data):
        return []
    found: list[Problem] = []
    stack: list[tuple[tuple[Any, ...], Any]] = [((), data)]
    while stack:
        loc, value = stack.pop()
        if isinstance(value, str):
            found += _lone_surrogate(file, loc, value, "text")
        elif isinstance(value, dict):
            for key in value:
                found += _lone_surrogate(file, loc + (_escaped(key),), key, "key")
            stack.extend((loc + (_escaped(k),), v) for k, v in reversed(list(value.items())))
        elif isinstance(value, list):
            stack.extend((loc + (i,), v) for i, v in reversed(list(enumerate(value))))
    return found


def all_text(data: Any) -> bool:
    """Whether every string of ``data`` (values and keys) is text, told at C speed: its JSON,
    written without escapes, is UTF-8 exactly when it holds no lone surrogate. ``False`` when
    that cannot be told so (a value JSON cannot write, a document nesting too deeply): the
    walk then decides."""
    try:
        json.dumps(data, ensure_ascii=False, check_circular=False).encode("utf-8")
    except (UnicodeEncodeError, TypeError, ValueError, RecursionError):
        return False
    return True


def _lone_surrogate(file: str, loc: tuple[Any, ...], text: str, what: str) -> list[Problem]:
    hit = _SURROGATE.search(text)
    if hit is None:
        return []
    return [
        Problem(
            file,
            json_path(loc),
            (
                f"{what} holds {_escaped(hit.group())} at character {hit.start()}, a lone surrogate: not Unicode text, "
                "and no results, report or export file can hold it (write the character meant)"
            ),
        )
    ]


def folder_name_problem(rel: str) -> Problem | None:
    """A :class:`Problem` when the house folder ``rel`` (relative to the dataset) has a name that
    is not UTF-8: Python reads such bytes as lone surrogates, and the name is the house id every
    row and export holds. ``None`` when the name is text."""
    hit = _SURROGATE.search(rel)
    if hit is None:
        return None
    return Problem(
        _escaped(rel),
        "$",
        (
            f"the folder name is not UTF-8 text ({_escaped(hit.group())} at character {hit.start()}), and no results, "
            "report or export file can hold a house id made from it: rename the folder"
        ),
    )


_FRIENDLY = {
    "missing": "required field '{field}' is missing",
    "enum": "{msg}",
}


def problems_from_validation_error(file: str, err: ValidationError, prefix: tuple[Any, ...] = ()) -> list[Problem]:
    """One :class:`Problem` per pydantic error, with a sentence a person can act on."""
    out: list[Problem] = []
    for e in err.errors(include_url=False):
        loc = prefix + tuple(e["loc"])
        kind = e["type"]
        if kind == "non_finite":  # raised by a record for one of its numbers
            loc = loc + tuple(e["ctx"]["at"])
        field = str(loc[-1]) if loc else ""
        if kind == "missing":
            msg = f"required field '{field}' is missing"
        elif loc and loc[-1] == "[key]":
            msg = f"unknown key {e.get('input')!r}: {e['msg'][0].lower() + e['msg'][1:]}"
        elif kind == "non_finite":
            msg = f"'{field}' {non_finite_message(e['ctx']['value'])}"
        elif kind in ("too_short", "too_long") and isinstance(e.get("input"), list):
            msg = f"'{field}' has {len(e['input'])} items: {e['msg']}"
        else:
            shown = e.get("input")
            text = repr(shown)
            if len(text) > 60:
                text = text[:57] + "..."
            msg = f"'{field}' {e['msg'][0].lower() + e['msg'][1:]} (got {text})"
        out.append(Problem(file, json_path(loc), msg))
    return out

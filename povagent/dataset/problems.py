"""Problems found in a dataset: file, JSON path and a plain sentence.

Shared by loading (which reports a bad house and goes on) and ``povagent validate`` (which
reports every problem). Converts pydantic and jsonschema errors into readable sentences.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable

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


_FRIENDLY = {
    "missing": "required field '{field}' is missing",
    "enum": "{msg}",
}


def problems_from_validation_error(file: str, err: ValidationError, prefix: tuple[Any, ...] = ()) -> list[Problem]:
    """One :class:`Problem` per pydantic error, with a sentence a person can act on."""
    out: list[Problem] = []
    for e in err.errors(include_url=False):
        loc = prefix + tuple(e["loc"])
        field = str(loc[-1]) if loc else ""
        kind = e["type"]
        if kind == "missing":
            msg = f"required field '{field}' is missing"
        elif loc and loc[-1] == "[key]":
            msg = f"unknown key {e.get('input')!r}: {e['msg'][0].lower() + e['msg'][1:]}"
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

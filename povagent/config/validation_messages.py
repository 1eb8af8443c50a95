"""Validation errors as people read them: one line per problem, with the file, the line and the nearest valid name.

pydantic reports a problem as a location and a message; :func:`validation_message` turns each
into ``file, line N: key.path: what is wrong`` (an unknown key with the keys allowed there and
a "did you mean", a missing key, a value out of its enum with the near choice), using the lines
the reader kept (:class:`~povagent.config.yaml_reader.ConfigSource`).

This module only words messages: it must not read files or validate anything itself.
"""

from __future__ import annotations

import re
from typing import Any, Mapping, Union, get_args, get_origin

from pydantic import BaseModel, ValidationError

from povagent.config.quoting import Loc, cut, dotted, shown
from povagent.config.yaml_reader import ConfigSource
from povagent.plugins import did_you_mean


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    # the runtime class of typing.Union objects, not an annotation
    if get_origin(annotation) is not None or isinstance(annotation, type(Union[int, str])):  # noqa: UP007
        for arg in get_args(annotation):
            found.extend(_models_in(arg))
    return found


def _model_at(model: type[BaseModel], loc: Loc) -> type[BaseModel] | None:
    for part in loc:
        if isinstance(part, int):
            continue
        info = model.model_fields.get(part)
        if info is None:
            return None
        nested = _models_in(info.annotation)
        if not nested:
            return None
        model = nested[0]
    return model


def _clean_loc(loc: Loc) -> Loc:
    # pydantic inserts validator tags (e.g. 'function-before[...]') into locations; drop them.
    return tuple(p for p in loc if isinstance(p, int) or not ("[" in p or p in ("str", "int", "list[int]")))


_QUOTED = re.compile(r"'([^']*)'")


def options_message(component: str, exc: ValidationError, model: type[BaseModel], unknown: Mapping[str, str] | None = None) -> str:
    """A plugin's YAML ``options`` refused by its ``model``, one ``component: option 'key': why``
    per problem joined by ``; ``; an unknown option lists the known ones (``unknown`` words a
    key that is unknown for a reason of its own)."""
    lines = []
    for err in exc.errors():
        field = ".".join(str(p) for p in err["loc"]) or "options"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = (unknown or {}).get(str(err["loc"][0]) if err["loc"] else "", f"unknown option (known: {sorted(model.model_fields)})")
        lines.append(f"{component}: option '{field}': {msg}")
    return "; ".join(lines)


def validation_message(exc: ValidationError, model: type[BaseModel], source: ConfigSource, prefix: Loc = ()) -> str:
    """One line per pydantic error: ``file, line N: field: message (did you mean ...?)``."""
    out: list[str] = []
    for err in exc.errors():
        loc = prefix + _clean_loc(tuple(err["loc"]))
        where = source.where(loc)
        if err["type"] == "extra_forbidden":
            parent = _model_at(model, _clean_loc(tuple(err["loc"]))[:-1])
            allowed = list(parent.model_fields) if parent else []
            bad = loc[-1]
            section = dotted(loc[:-1]) if loc[:-1] else "the top level"
            out.append(f"{where}: unknown key {shown(bad)} in {section}{did_you_mean(cut(str(bad)), allowed)}; allowed: {', '.join(allowed)}")
        elif err["type"] == "missing":
            out.append(f"{where}: {dotted(loc)}: required key is missing")
        else:
            msg = err["msg"].removeprefix("Value error, ")
            if err["type"] == "enum":
                expected = err.get("ctx", {}).get("expected", "")
                choices = _QUOTED.findall(expected)
                msg = f"{shown(err['input'])} is not one of {expected}{did_you_mean(cut(str(err['input'])), choices)}"
            out.append(f"{where}: {dotted(loc)}: {msg}")
    return "\n".join(out)

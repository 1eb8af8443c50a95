"""A model's turns written down in a file, for the loopback server to replay: a stand-in for a
tool-calling model.

What it is for: the active mode (and any strategy that offers tools) needs a model that calls
tools; the loopback server's fixed reply answers on the first turn with no call at all. A turns
file lists what the model says, turn by turn, each a text or some tool calls (or both), and
``python -m povagent.testing.loopback_server --script TURNS`` answers the first requests with
them, in order, before its fixed reply::

    # turns.yaml (JSON works too: it is YAML)
    - tool_calls:
        - {name: go_to_frame, arguments: {frame: 1}}
        - {name: turn, arguments: {degrees: 30}}
    - tool_calls:
        - {name: answer, arguments: {image: view 2, x: 256, y: 256}}
    - '{"selected_image": 0, "x": 256, "y": 256}'     # a turn of plain text

A call's ``arguments`` are a mapping (sent as JSON) or a string sent exactly as written (so a
file can hold the malformed arguments a real model sends). The file is untrusted input: it is
read with the config reader (safe loader, bounded size, nesting and aliases), and a malformed
turn is one :class:`~povagent.errors.ConfigError` naming the file, the line and the field. What
this module must not do: serve anything (the server does), or run anything a file names.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

from povagent.config.quoting import Loc, dotted, shown
from povagent.config.yaml_reader import ConfigSource, read_yaml
from povagent.errors import ConfigError

__all__ = ["Turn", "read_turns", "turns_of"]

@dataclass(frozen=True)
class Turn:
    """One turn of the model: its text (``None``: ``content: null``) and its tool calls, each
    ``{"name": ..., "arguments": <mapping, or text sent as it is>}`` (the server's ``Reply``
    takes both as they are)."""

    text: str | None
    tool_calls: tuple[dict[str, Any], ...] = ()


#: The keys a turn given as a mapping may hold, and those of one tool call.
TURN_KEYS = ("text", "tool_calls")
CALL_KEYS = ("name", "arguments")
#: The most tool calls one turn may hold (a real model sends a handful; tests of floods, 100).
MAX_CALLS_PER_TURN = 1000


def read_turns(path: str | os.PathLike[str]) -> list[Turn]:
    """The turns of a JSON or YAML turns file, in order (``LoopbackServer.script`` queues them)."""
    return turns_of(read_yaml(path))


def turns_of(source: ConfigSource) -> list[Turn]:
    """The turns of an already parsed document (see the module docstring for its shape)."""
    if not isinstance(source.data, list) or not source.data:
        raise ConfigError(f"{source.where()}: a turns file is a list of turns, each a text or {{tool_calls: [...]}} (got {shown(source.data)})")
    return [_turn(source, turn, (i,)) for i, turn in enumerate(source.data)]


def _problem(source: ConfigSource, loc: Loc, what: str) -> ConfigError:
    """One line: the file and line, the turn (from 1) and the field within it."""
    field = f", field {dotted(loc[1:])}" if len(loc) > 1 else ""
    return ConfigError(f"{source.where(loc)}: turn {loc[0] + 1}{field}: {what}")


def _turn(source: ConfigSource, turn: Any, loc: Loc) -> Turn:
    if isinstance(turn, str):
        return Turn(turn)
    if not isinstance(turn, dict):
        raise _problem(source, loc, f"a turn is a text or a mapping with {' and/or '.join(TURN_KEYS)}, got {shown(turn)}")
    unknown = [k for k in turn if k not in TURN_KEYS]
    if unknown:
        raise _problem(source, loc + (unknown[0],), f"unknown key (a turn holds {', '.join(TURN_KEYS)})")
    text = turn.get("text")
    if text is not None and not isinstance(text, str):
        raise _problem(source, loc + ("text",), f"must be a text, got {shown(text)}")
    calls = turn.get("tool_calls", [])
    if not isinstance(calls, list) or len(calls) > MAX_CALLS_PER_TURN:
        raise _problem(source, loc + ("tool_calls",), f"must be a list of at most {MAX_CALLS_PER_TURN} calls, each {{name: ..., arguments: {{...}}}}")
    if text is None and not calls:
        raise _problem(source, loc, "a turn needs a text or at least one tool call")
    return Turn(text, tool_calls=tuple(_call(source, call, loc + ("tool_calls", k)) for k, call in enumerate(calls)))


def _call(source: ConfigSource, call: Any, loc: Loc) -> dict[str, Any]:
    if not isinstance(call, dict):
        raise _problem(source, loc, f"a tool call is {{name: ..., arguments: {{...}}}}, got {shown(call)}")
    unknown = [k for k in call if k not in CALL_KEYS]
    if unknown:
        raise _problem(source, loc + (unknown[0],), f"unknown key (a tool call holds {', '.join(CALL_KEYS)})")
    name = call.get("name")
    if not isinstance(name, str) or not name:
        raise _problem(source, loc + ("name",), f"the tool's name is required, as a text (got {shown(name)})")
    arguments = call.get("arguments", {})
    if not isinstance(arguments, (dict, str)):
        raise _problem(source, loc + ("arguments",), f"a mapping, or a text sent as it is, got {shown(arguments)}")
    try:
        json.dumps(arguments, allow_nan=False)
    except (TypeError, ValueError):  # YAML reads 2024-01-01 as a date, .nan as NaN: neither is JSON
        raise _problem(source, loc + ("arguments",), "holds a value JSON cannot carry (a date, NaN, infinity): quote it") from None
    return {"name": name, "arguments": arguments}

"""How a config's values and places are quoted back in error messages.

A config is untrusted input: a value it holds may be megabytes long, so every value or name
quoted back is cut short (:func:`shown`, :func:`cut`), and a place in a document is written as
the dotted key path a person would type (:func:`dotted`: ``backend.options.model``,
``scorers[1]``). The reader (:mod:`povagent.config.yaml_reader`), the validation messages and
the plugin checks all quote through here, so a message never repeats a hostile value whole.

Pure text: this module must not read files or know the pipeline's keys.
"""

from __future__ import annotations

from typing import Any

#: A place in a YAML document: its keys and list indices from the top (``("scorers", 1)``).
Loc = tuple[Any, ...]

#: Longest user value quoted back in a message.
_SHOWN = 80


def shown(value: Any) -> str:
    """``repr(value)``, cut to a readable length (a hostile config may hold megabytes)."""
    text = repr(value) if not isinstance(value, str) else repr(value if len(value) <= _SHOWN else value[:_SHOWN] + "...")
    return text if len(text) <= _SHOWN + 10 else text[:_SHOWN] + "..."


def cut(name: str) -> str:
    """A user-written name cut for messages and name suggestions (difflib is quadratic)."""
    return name if len(name) <= _SHOWN else name[:_SHOWN] + "..."


def dotted(loc: Loc) -> str:
    """``loc`` as a dotted key path (``backend.options.model``, ``scorers[1]``; ``(top level)``)."""
    out = ""
    for p in loc:
        out += f"[{p}]" if isinstance(p, int) else (f".{cut(str(p))}" if out else cut(str(p)))
    return out or "(top level)"

"""Which registered scorer follows which scoring protocol (:data:`~povagent.interfaces.ScoreProtocol`).

The summary and the report break a protocol's fields down in sections of their own (the
official error tables, the success-rate tables); they learn which scorer's fields those are
from the scorer itself (``Scorer.protocol``), asked through the plugin registry, never from a
scorer's name. A scorer that declares no protocol is shown through its declared metrics only.

Only a lookup: nothing here reads a run folder or scores a row.
"""

from __future__ import annotations

from typing import Any, Mapping, get_args

from povagent.interfaces import ScoreProtocol

#: Every protocol, in the order reports show their sections.
PROTOCOLS: tuple[ScoreProtocol, ...] = get_args(ScoreProtocol)


def registered_protocols() -> dict[str, ScoreProtocol]:
    """``{scorer name: protocol}`` for every registered scorer that declares one.

    A plugin that fails to load does not hide the built-in scorers' protocols: reading a run's
    scores never depends on every installed plugin loading."""
    from povagent.errors import PluginError
    from povagent.plugins import build_plugin_host, get_plugin_host

    try:
        host = get_plugin_host()
    except PluginError:
        host = build_plugin_host(strict=False)
    return {e.name: p for e in host.entries("scorer") if (p := getattr(e.factory, "protocol", None)) in PROTOCOLS}


def scorer_protocols(scorers: Mapping[str, Any]) -> dict[str, ScoreProtocol]:
    """``{name: protocol}`` of a run's scorer objects (or factories) that follow one."""
    return {name: p for name, s in scorers.items() if (p := getattr(s, "protocol", None)) in PROTOCOLS}


def following(protocols: Mapping[str, str], protocol: str, scores: Mapping[str, Any] | None = None) -> str | None:
    """The scorer of ``protocols`` that follows ``protocol``: the one whose fields ``scores`` (a
    row's) carry, else the first; ``None`` when none follows it."""
    names = [n for n, p in protocols.items() if p == protocol]
    return next((n for n in names if scores and n in scores), names[0] if names else None)

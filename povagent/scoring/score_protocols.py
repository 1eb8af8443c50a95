"""Which registered scorer follows which scoring protocol (:data:`~povagent.interfaces.ScoreProtocol`).

The summary and the report break a protocol's fields down in sections of their own (the
official error tables, the success-rate tables); they learn which scorer's fields those are
from the scorer itself (``Scorer.protocol``), asked through the plugin registry, never from a
scorer's name. A scorer that declares no protocol is shown through its declared metrics only.

The same registry shows a row's typed prediction (:func:`shown_answer`). Only lookups: nothing
here reads a run folder or scores a row.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Protocol, TypeVar, get_args

from povagent.interfaces import Diagnosis, ScoreProtocol

if TYPE_CHECKING:
    from povagent.plugins import PluginHost


class _Declared(Protocol):
    """A declared metric as a scorer (:class:`~povagent.scoring.metrics.Metric`) or a summary
    records it: the row field it reads."""

    @property
    def field(self) -> str: ...


_M = TypeVar("_M", bound=_Declared)

#: Every protocol, in the order reports show their sections.
PROTOCOLS: tuple[ScoreProtocol, ...] = get_args(ScoreProtocol)
#: Every diagnosis a scorer may declare.
DIAGNOSES: tuple[Diagnosis, ...] = get_args(Diagnosis)

#: The row fields each protocol's own sections read (the official error tables: the error, its
#: strict variant, the GT in or behind the frame; the success tables: the hit), beside
#: ``answered`` (the response rate). A metric a protocol's scorer declares over one of them is
#: shown there; every other metric it declares is shown as any scorer's is
#: (:func:`beyond_protocol`), so a metric added to the scorer needs no line elsewhere.
PROTOCOL_FIELDS: dict[str, frozenset[str]] = {
    "normalized_l2": frozenset({"answered", "l2", "l2_strict", "gt_in_frame", "gt_behind"}),
    "marked_hit": frozenset({"answered", "success"}),
}


def beyond_protocol(declared: Mapping[str, _M], protocol: str | None) -> dict[str, _M]:
    """The metrics of ``declared`` (``{name: metric}``, each with its row ``field``) that the
    sections of ``protocol`` (the scorer's; ``None``: it follows none) do not show."""
    shown = PROTOCOL_FIELDS.get(protocol, frozenset()) if protocol is not None else frozenset()
    return {name: m for name, m in declared.items() if m.field not in shown}


def reading_host() -> PluginHost:
    """The plugin host a reader of run folders asks (the process's own). A plugin that fails to
    load hides only what it registers: reading a run's scores never depends on every installed
    plugin loading."""
    from povagent.errors import PluginError
    from povagent.plugins import build_plugin_host, get_plugin_host

    try:
        return get_plugin_host()
    except PluginError:
        return build_plugin_host(strict=False)


def registered_protocols() -> dict[str, ScoreProtocol]:
    """``{scorer name: protocol}`` for every registered scorer that declares one."""
    return {e.name: p for e in reading_host().entries("scorer") if (p := getattr(e.factory, "protocol", None)) in PROTOCOLS}


#: The last :func:`diagnosing_scorers` answer, with the registry table it was read from.
_diagnosing: tuple[Any, dict[str, str]] | None = None


def diagnosing_scorers() -> dict[str, str]:
    """``{diagnosis: scorer name}`` of the registered scorers that declare one (``Scorer.diagnosis``;
    the first by name for each): where a row's diagnostics are. Read again only when the registry
    changes (a row at a time asks it)."""
    global _diagnosing
    table = reading_host()._table("scorer")
    if _diagnosing is not None and _diagnosing[0] is table:
        return _diagnosing[1]
    found: dict[str, str] = {}
    for name in sorted(table):
        kind = getattr(table[name].factory, "diagnosis", None)
        if kind in DIAGNOSES and kind not in found:
            found[kind] = name
    _diagnosing = (table, found)
    return found


def shown_answer(answer_type: str | None, value: Mapping[str, Any] | None) -> str | None:
    """A row's typed prediction as its answer type shows it (``AnswerType.show``); ``None`` for a
    row without a typed value, or of a type no plugin registers here."""
    if answer_type is None or value is None:
        return None
    host = reading_host()
    return host.answer_type(answer_type).show(value) if answer_type in host.names("answer_type") else None


def scorer_protocols(scorers: Mapping[str, Any]) -> dict[str, ScoreProtocol]:
    """``{name: protocol}`` of a run's scorer objects (or factories) that follow one."""
    return {name: p for name, s in scorers.items() if (p := getattr(s, "protocol", None)) in PROTOCOLS}


def following(protocols: Mapping[str, str], protocol: str, scores: Mapping[str, Any] | None = None) -> str | None:
    """The scorer of ``protocols`` that follows ``protocol``: the one whose fields ``scores`` (a
    row's) carry, else the first; ``None`` when none follows it."""
    names = [n for n, p in protocols.items() if p == protocol]
    return next((n for n in names if scores and n in scores), names[0] if names else None)

"""The rules a set's replies are scored by in a second opinion (``povagent rescore-log``): the set's
official rule and every harness's rule povagent has for it, each a registered parser and scorer.

Nothing here names a set or a rule: the official rule is the set's format's (its official parser
and scorer), and a harness's rule is a registered parser that says which sets its harness reads
with it and with which scorer (``harness_sets``, ``(set, scorer)`` pairs, with ``source``, ``harness`` and
``harness_filter``: :class:`povagent_plugins.parsers.mcq.rule.RuleParser`). A set added later
plugs in by registering its format and its rule parsers; this module does not change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from povagent.errors import PluginError


@dataclass(frozen=True)
class LogRule:
    """One way of scoring a set's replies: a parser (the rule) and the scorer that counts its hits."""

    #: How tables and JSON name it: the parser's name (with ``+scorer`` where the set's rules share a parser).
    name: str
    parser: str
    scorer: str
    #: Where the rule comes from, ``owner/repo@commit``.
    source: str
    #: Whose rule it is (``lmms-eval``, ``VLMEvalKit``, the set's own code).
    harness: str
    #: The set's official rule (listed first).
    official: bool
    #: The filter the rule applies to the reply before reading it, as its harness does (``""``: none).
    harness_filter: str = ""


def official_rules(host: Any) -> Mapping[str, tuple[str, str, str]]:
    """``{set: (official parser, official scorer, source)}`` of every set whose format declares them."""
    from povagent.dataset.choice_sets import OFFICIAL_SET_PARSERS, OFFICIAL_SET_SCORERS

    return {key: (parser, OFFICIAL_SET_SCORERS[key], _declared(host, parser, "source")) for key, parser in OFFICIAL_SET_PARSERS.items()}


def known_sets(host: Any) -> list[str]:
    """The sets a log can be scored as: those with an official rule."""
    return sorted(official_rules(host))


def _declared(host: Any, parser: str, attribute: str) -> str:
    """What the parser registered as ``parser`` declares as ``attribute`` (``""``: nothing)."""
    try:
        return str(getattr(host.entry("parser", parser).factory, attribute, "") or "")
    except PluginError:
        return ""


def set_rules(host: Any, set_name: str) -> list[LogRule]:
    """The set's official rule, then every registered harness rule for it (by parser name).

    :class:`~povagent.errors.PluginError` for a set with no official rule, naming the known sets."""
    official = official_rules(host)
    if set_name not in official:
        raise PluginError(f"unknown set {set_name!r}: a log can be scored as {', '.join(sorted(official))}")
    parser, scorer, source = official[set_name]
    found = [(parser, scorer, source, _declared(host, parser, "harness") or "the set's own code", True, _declared(host, parser, "harness_filter"))]
    for entry in host.entries("parser"):
        scorers = dict(getattr(entry.factory, "harness_sets", None) or ())
        if set_name in scorers and (entry.name, scorers[set_name]) != (parser, scorer):
            found.append((entry.name, str(scorers[set_name]), _declared(host, entry.name, "source"), _declared(host, entry.name, "harness"), False,
                          _declared(host, entry.name, "harness_filter")))  # fmt: skip
    shared = {p for p, *_ in found if sum(1 for q, *_ in found if q == p) > 1}
    return [LogRule(p if p not in shared else f"{p}+{s}", p, s, src, h, o, f) for p, s, src, h, o, f in found]

"""The rules a set's replies are scored by in a second opinion (``povagent rescore-log``): the set's
official rule and every harness's rule povagent has for it, each a registered parser and scorer.

Nothing here names a set or a rule: the official rule is the set's registered dataset format's
(:class:`~povagent.dataset.formats.DatasetFormat`: its official parser and scorer), and a
harness's rule is a registered parser that says which sets its harness reads with it and with
which scorer (``harness_sets``, ``(set, scorer)`` pairs, with ``source``, ``harness`` and
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


#: The answer types a logged reply can be scored as: a reply and a question's labelled options,
#: or a reply and a gold number (a set mixing both, as VSI-Bench does).
LOGGED_ANSWER_TYPES = ("choice", "choice-or-number", "number")


def official_rules(host: Any) -> Mapping[str, tuple[str, str, str]]:
    """``{set: (official parser, official scorer, source)}`` of every registered dataset format
    whose records ask for an answer type a log can be scored as (:data:`LOGGED_ANSWER_TYPES`).
    The source is the one the official parser declares (the rule's own commit), else the format's."""
    from povagent.dataset.formats import registered_formats

    return {
        key: (fmt.official_parser, fmt.official_scorer, _declared(host, fmt.official_parser, "source") or fmt.source)
        for key, fmt in registered_formats(host).items()
        if fmt.answer_type in LOGGED_ANSWER_TYPES
    }


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
        kinds = ", ".join(LOGGED_ANSWER_TYPES)
        raise PluginError(
            f"unknown set {set_name!r}: a log can be scored as {', '.join(sorted(official))} (the registered formats whose answer type is one of {kinds})"
        )
    parser, scorer, source = official[set_name]
    found = [(parser, scorer, source, _declared(host, parser, "harness") or "the set's own code", True, _declared(host, parser, "harness_filter"))]
    for entry in host.entries("parser"):
        scorers = dict(getattr(entry.factory, "harness_sets", None) or ())
        if set_name in scorers and (entry.name, scorers[set_name]) != (parser, scorer):
            found.append(
                (
                    entry.name,
                    str(scorers[set_name]),
                    _declared(host, entry.name, "source"),
                    _declared(host, entry.name, "harness"),
                    False,
                    _declared(host, entry.name, "harness_filter"),
                )
            )
    shared = {p for p, *_ in found if sum(1 for q, *_ in found if q == p) > 1}
    return [LogRule(p if p not in shared else f"{p}+{s}", p, s, src, h, o, f) for p, s, src, h, o, f in found]

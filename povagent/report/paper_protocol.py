"""Which rows the paper's protocol covers: the authors ran some strategies on some conditions only.

They ran the interventions (O-Plot, O&A-Plot, CoT, S-CoT) on Inferred and Stated, never on
Given. A strategy class says which conditions the paper ran it on with a ``paper_conditions``
attribute (the built-in strategies do); rows of other conditions are outside the paper's
protocol, and the paper-layout tables leave them out unless asked to keep them. A strategy
without the attribute, or one the plugin host does not know, counts as covering every condition.

Only a lookup: it reads the strategy's class from the plugin host, never builds one.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from povagent.errors import PluginError


def paper_conditions(strategy: str, host: Any = None) -> frozenset[str] | None:
    """The condition codes the paper ran ``strategy`` on, or ``None`` (every condition / unknown)."""
    if host is None:
        return _default_host_conditions(strategy)
    return _conditions_of(strategy, host)


@lru_cache(maxsize=64)
def _default_host_conditions(strategy: str) -> frozenset[str] | None:
    from povagent.plugins import get_plugin_host

    return _conditions_of(strategy, get_plugin_host())


def _conditions_of(strategy: str, host: Any) -> frozenset[str] | None:
    try:
        factory = host.entry("strategy", strategy).factory
    except (PluginError, ValueError):
        return None
    conditions = getattr(factory, "paper_conditions", None)
    return None if conditions is None else frozenset(str(c) for c in conditions)


def outside_paper_protocol(strategy: str, condition: str, host: Any = None) -> bool:
    """Whether a row of ``strategy`` on ``condition`` is one the authors never ran."""
    covered = paper_conditions(strategy, host)
    return covered is not None and str(condition) not in covered

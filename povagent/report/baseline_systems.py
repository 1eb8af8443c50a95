"""Which systems of a report are baselines, not models: reference rows, never bolded as "best".

A sweep cell is a baseline when its backend's plugin declares itself one
(:attr:`povagent.interfaces.Backend.offline_baseline`: the centre, random and oracle guesses, the
simulations answering from the records, the active mode's explorers), or when its label or axes
name the center guess. The declaration is read from the backend's class through the plugin
host, never from a list of names here, so a new offline backend is a baseline by saying so in
its own file. Collecting folders, the tables and the official-parse table all ask the same
question here, so the answer cannot drift between them.

This module only reads labels, axis values and the backends' declarations: it never builds a
backend, reads a run folder or computes a score (the computed center baseline is
:mod:`povagent.report.baseline`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from povagent.errors import PluginError


def is_center_system(axes: dict[str, str], label: str) -> bool:
    """True when a sweep cell already is a center baseline (its backend or model says so)."""
    names = [label, axes.get("backend", ""), axes.get("model", ""), axes.get("strategy", "")]
    return any("center" in n.lower() or "centre" in n.lower() for n in names)


def declared_offline_baseline(backend: str, host: Any = None) -> bool:
    """Whether the backend registered as ``backend`` declares itself an offline baseline (a
    backend the plugin host does not know, or none, is not one)."""
    if not backend:
        return False
    if host is None:
        return _default_host_declares(backend)
    return _declares(backend, host)


@lru_cache(maxsize=64)
def _default_host_declares(backend: str) -> bool:
    from povagent.plugins import get_plugin_host

    return _declares(backend, get_plugin_host())


def _declares(backend: str, host: Any) -> bool:
    try:
        factory = host.entry("backend", backend).factory
    except (PluginError, ValueError):
        return False
    return getattr(factory, "offline_baseline", False) is True


def is_baseline_system(axes: dict[str, str], label: str, host: Any = None) -> bool:
    """True for a baseline cell (a center guess, or a backend declared an offline baseline):
    a reference row in tables, styled and sorted as a baseline, never bolded as best."""
    return is_center_system(axes, label) or declared_offline_baseline(axes.get("backend", ""), host)

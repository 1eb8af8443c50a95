"""Which systems of a report are baselines, not models: reference rows, never bolded as "best".

A sweep cell is a baseline when its backend is one (``center``, ``random``, ``oracle``, or a
simulation answering from the records: ``simulated``, ``planted``), or when its label or axes
name the center guess. Collecting folders, the tables and the official-parse table all ask the
same question here, so the answer cannot drift between them.

This module only reads labels and axis values: it never reads a run folder or computes a score
(the computed center baseline is :mod:`povagent.report.baseline`).
"""

from __future__ import annotations


def is_center_system(axes: dict[str, str], label: str) -> bool:
    """True when a sweep cell already is a center baseline (its backend or model says so)."""
    names = [label, axes.get("backend", ""), axes.get("model", ""), axes.get("strategy", "")]
    return any("center" in n.lower() or "centre" in n.lower() for n in names)


#: Backends that are baselines, not models: shown as reference rows, never bolded as "best".
#: ``simulated`` is a perception simulation and ``planted`` a behaviour simulation (both answer
#: from the records): not models either.
BASELINE_BACKENDS = frozenset({"center", "random", "oracle", "simulated", "planted"})


def is_baseline_system(axes: dict[str, str], label: str) -> bool:
    """True for a baseline cell (center, random, oracle backends): a reference row in tables."""
    return is_center_system(axes, label) or axes.get("backend", "") in BASELINE_BACKENDS

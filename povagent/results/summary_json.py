"""Summaries as JSON a reader can always parse: a number that is not finite is written ``null``.

Summaries aggregate whatever the rows hold, and a row may hold NaN or an infinity (a model that
answered ``NaN``, a scorer's margin from it). JSON has no such numbers: Python's ``json`` writes
``NaN`` (which strict readers refuse) or, with ``allow_nan=False``, raises half-way through a
report. Every summary file (a run's and a sweep's ``summary.json``, the report's, ``compare.json``)
is written as :func:`summary_json_text`, which writes those numbers as ``null`` ("no number").
This module never decides what a summary holds; it only writes one.
"""

from __future__ import annotations

import json
import math
from typing import Any


def finite_json(value: Any) -> Any:
    """``value`` with every float that is not finite replaced by ``None`` (tuples become lists).

    Walks without recursion: a summary is wide, never deep, but nothing here should depend on it.
    """
    root: list[Any] = [None]
    stack: list[tuple[Any, list[Any] | dict[Any, Any], Any]] = [(value, root, 0)]
    while stack:
        item, parent, key = stack.pop()
        if isinstance(item, float) and not math.isfinite(item):
            parent[key] = None
        elif isinstance(item, dict):
            copy: dict[Any, Any] = {}
            parent[key] = copy
            for k, v in item.items():
                copy[k] = None
                stack.append((v, copy, k))
        elif isinstance(item, (list, tuple)):
            items: list[Any] = [None] * len(item)
            parent[key] = items
            stack.extend((v, items, i) for i, v in enumerate(item))
        else:
            parent[key] = item
    return root[0]


def summary_json_text(data: Any, indent: int | None = 1, default: Any = None) -> str:
    """``data`` as JSON text, non-finite numbers as ``null`` (``default`` as :func:`json.dumps`'s)."""
    try:
        return json.dumps(data, indent=indent, allow_nan=False, default=default)
    except ValueError:  # a number that is not finite somewhere: the walk costs only then
        return json.dumps(finite_json(data), indent=indent, allow_nan=False, default=default)

"""Summaries of scored rows: means over answered rows with the response rate beside each.

The official numbers: mean normalized L2 over answered instances only; response rate =
answered / total; share of answered rows whose GT lies in the scored frame. Broken down overall,
per condition, per direction and per condition x direction.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass
from typing import Any, Iterable

from povagent.dataset.models import CONDITIONS, DIRECTIONS


@dataclass(frozen=True)
class ScoredRow:
    """The few fields a summary needs from a row."""

    condition: str
    direction: str
    answered: bool
    l2: float | None
    gt_in_frame: bool | None
    l2_strict: float | None = None


def summarize(rows: Iterable[ScoredRow]) -> dict[str, Any]:
    """One cell: ``n`` (answered), ``n_total``, ``response_rate``, ``mean_l2``, ``std_l2``
    (population std), ``pct_in_frame`` (percent of answered), ``mean_l2_strict``."""
    rows = list(rows)
    answered = [r for r in rows if r.answered and r.l2 is not None]
    n, total = len(answered), len(rows)
    errs = [r.l2 for r in answered]
    mean = sum(errs) / n if n else None
    std = math.sqrt(sum((e - mean) ** 2 for e in errs) / n) if n else None
    in_frame = sum(1 for r in answered if r.gt_in_frame)
    strict = [r.l2_strict for r in answered if r.l2_strict is not None]
    return {
        "n": n,
        "n_total": total,
        "response_rate": n / total if total else None,
        "mean_l2": mean,
        "std_l2": std,
        "pct_in_frame": 100.0 * in_frame / n if n else None,
        "mean_l2_strict": sum(strict) / len(strict) if strict else None,
    }


def breakdown(rows: Iterable[ScoredRow]) -> dict[str, Any]:
    """``overall``, ``per_condition``, ``per_direction`` and ``per_condition_direction``."""
    rows = list(rows)
    by_c: dict[str, list[ScoredRow]] = defaultdict(list)
    by_d: dict[str, list[ScoredRow]] = defaultdict(list)
    by_cd: dict[str, list[ScoredRow]] = defaultdict(list)
    for r in rows:
        by_c[r.condition].append(r)
        by_d[r.direction].append(r)
        by_cd[f"{r.condition}/{r.direction}"].append(r)
    c_order = [str(c) for c in CONDITIONS]
    d_order = [str(d) for d in DIRECTIONS]
    return {
        "overall": summarize(rows),
        "per_condition": {c: summarize(by_c[c]) for c in c_order if c in by_c},
        "per_direction": {d: summarize(by_d[d]) for d in d_order if d in by_d},
        "per_condition_direction": {
            f"{c}/{d}": summarize(by_cd[f"{c}/{d}"]) for c in c_order for d in d_order if f"{c}/{d}" in by_cd
        },
    }

"""``summary.json``'s ``diagnostics`` section: why answers failed, per condition (an addition).

Built from the rows' ``diagnose`` and ``relation`` scores (:mod:`povagent.scoring.diagnosis`),
beside the official breakdown, never instead of it. Per condition:

* ``failure_steps``: the share of answered rows whose first failing step is ``frame``,
  ``anchor``, ``viewpoint``, ``placement``, or that are ``correct`` (shares of ``n_diagnosed``);
* ``egocentric_bias``: among answered rows where the egocentric and the observer-relative
  targets lie more than the margin apart in the answered frame (``bias_n`` of them), the share
  nearer the egocentric one; with several runs, the mean over instances of each instance's share.
  ``egocentric_bias_ci`` is its 95% percentile bootstrap interval, resampling instances
  (:func:`povagent.scoring.bootstrap.bootstrap_mean_ci`). ``None`` for C (Given), where the
  observer view is the camera and the two targets coincide, and wherever no row is eligible;
* ``relation_success``: the share of answered rows whose point lies in the relation region
  (``relation_n`` of them), and ``per_direction`` the same beside the official mean L2 of those
  rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable

from povagent.scoring.bootstrap import DEFAULT_BOOT, bootstrap_mean_ci
from povagent.scoring.diagnosis import STEPS

#: What every ``diagnostics`` section says of itself.
LABEL = "addition, not in the paper: first failing step, egocentric bias and relation-consistent success (docs/how-to/why-models-fail.md)"


@dataclass(frozen=True, slots=True)
class DiagnosedRow:
    """The fields of one row the section needs (``None``: that scorer did not score the row)."""

    instance_id: str
    condition: str
    direction: str
    l2: float | None
    step: str | None
    nearer_egocentric: bool | None
    relation: bool | None


def _share(values: list[bool]) -> float | None:
    return sum(values) / len(values) if values else None


def _bias(rows: list[DiagnosedRow], n_boot: int | None, seed: int) -> tuple[float | None, list[float] | None, int]:
    votes: dict[str, list[bool]] = {}
    for r in rows:
        if r.nearer_egocentric is not None:
            votes.setdefault(r.instance_id, []).append(r.nearer_egocentric)
    if not votes:
        return None, None, 0
    estimate = bootstrap_mean_ci([sum(v) / len(v) for v in votes.values()], n_boot=DEFAULT_BOOT if n_boot is None else n_boot, seed=seed)
    ci = None if estimate.lo is None or estimate.hi is None else [estimate.lo, estimate.hi]
    return estimate.value, ci, sum(len(v) for v in votes.values())


def _group(rows: list[DiagnosedRow], with_bias: bool, n_boot: int | None, seed: int) -> dict[str, Any]:
    stepped = [r.step for r in rows if r.step is not None]
    related = [r for r in rows if r.relation is not None]
    out: dict[str, Any] = {
        "n_diagnosed": len(stepped),
        "failure_steps": {s: (stepped.count(s) / len(stepped) if stepped else None) for s in STEPS},
    }
    if with_bias:
        value, ci, n = _bias(rows, n_boot, seed)
        out.update({"egocentric_bias": value, "egocentric_bias_ci": ci, "bias_n": n})
    else:
        out.update({"egocentric_bias": None, "egocentric_bias_ci": None, "bias_n": 0, "egocentric_bias_note": "left out: in C the observer view is the camera"})
    out["relation_success"] = _share([bool(r.relation) for r in related])
    out["relation_n"] = len(related)
    per_direction: dict[str, Any] = {}
    for direction in sorted({r.direction for r in related}):
        here = [r for r in related if r.direction == direction]
        l2s = [r.l2 for r in here if r.l2 is not None]
        per_direction[direction] = {
            "n": len(here),
            "relation_success": _share([bool(r.relation) for r in here]),
            "official_mean_l2": sum(l2s) / len(l2s) if l2s else None,
        }
    out["per_direction"] = per_direction
    return out


def diagnostics_breakdown(rows: Iterable[DiagnosedRow], n_boot: int | None = None, seed: int = 0) -> dict[str, Any] | None:
    """The ``diagnostics`` section (``None`` when no row carries a diagnose or relation score);
    the bias index's interval from ``n_boot`` resamples (default: the reports' 2,000; 0: no
    interval) drawn with ``seed``."""
    rows = [r for r in rows if r.step is not None or r.relation is not None]
    if not rows:
        return None
    per_condition = {
        cond: _group([r for r in rows if r.condition == cond], cond != "c", n_boot, seed)
        for cond in sorted({r.condition for r in rows})
    }
    return {"label": LABEL, "per_condition": per_condition}

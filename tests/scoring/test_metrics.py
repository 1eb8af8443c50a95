"""Metrics a scorer declares: the one function turning a row into metric values, and their
breakdown per slice with a bootstrap CI."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric, row_metric_values, valued_row

ERROR = Metric("error", "lower", "mean", "err", "Error", "mean error over answered rows")
HITS = Metric("hit_rate", "higher", "rate", "hit", "Hit rate", "hits over every row", over="all")
MISSES = Metric("miss_share", "lower", "rate", "hit", "Misses", "misses over answered rows", negate=True)
DECLARED = {"mine": (ERROR, HITS, MISSES)}


def row(status: str, scores: dict, condition: str = "a", direction: str = "left"):
    return SimpleNamespace(status=status, scores=scores, condition=condition, direction=direction)


def test_an_answered_row_gives_every_declared_value():
    values = row_metric_values(row("answered", {"mine": {"answered": True, "err": 0.25, "hit": True}}), DECLARED)
    assert values == {"mine": {"error": 0.25, "hit_rate": 1.0, "miss_share": 0.0}}


def test_an_unanswered_row_counts_only_for_metrics_over_every_row_as_false():
    values = row_metric_values(row("parse_error", {}), DECLARED)
    assert values == {"mine": {"error": None, "hit_rate": 0.0, "miss_share": None}}


def test_a_row_the_scorer_scored_unanswered_is_not_an_answer():
    values = row_metric_values(row("answered", {"mine": {"answered": False, "err": 0.1, "hit": True}}), DECLARED)
    assert values["mine"] == {"error": None, "hit_rate": 0.0, "miss_share": None}


def test_a_non_finite_or_true_false_value_never_enters_a_mean():
    assert row_metric_values(row("answered", {"mine": {"err": float("nan"), "hit": False}}), DECLARED)["mine"]["error"] is None
    assert row_metric_values(row("answered", {"mine": {"err": True, "hit": False}}), DECLARED)["mine"]["error"] is None


def test_the_breakdown_holds_each_metric_per_slice_with_its_ci_and_what_was_declared():
    rows = [
        row("answered", {"mine": {"err": 0.2, "hit": True}}, "a", "left"),
        row("answered", {"mine": {"err": 0.4, "hit": False}}, "a", "right"),
        row("infra_error", {}, "b", "left"),
    ]
    out = metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=200)["mine"]
    assert out["declared"]["hit_rate"] == {"label": "Hit rate", "caption": "hits over every row", "better": "higher", "aggregation": "rate",
                                         "field": "hit", "over": "all", "negate": False}
    assert out["overall"]["error"]["value"] == pytest.approx(0.3) and out["overall"]["error"]["n"] == 2
    assert out["overall"]["hit_rate"]["value"] == pytest.approx(1 / 3) and out["overall"]["hit_rate"]["n"] == 3
    lo, hi = out["overall"]["error"]["ci_lo"], out["overall"]["error"]["ci_hi"]
    assert 0.2 <= lo <= 0.3 <= hi <= 0.4
    assert out["per_condition"]["b"]["hit_rate"]["value"] == 0.0 and out["per_condition"]["b"]["error"]["value"] is None
    assert set(out["per_direction"]) == {"left", "right"} and set(out["per_condition_direction"]) == {"a/left", "a/right", "b/left"}


def test_a_scorer_declaring_nothing_has_no_section():
    assert metrics_breakdown([valued_row(row("answered", {"quiet": {"x": 1}}), {"quiet": ()})], {"quiet": ()}) == {}


def test_a_declaration_as_a_summary_records_it_gives_the_metric_back():
    from povagent.scoring.metrics import Metric

    for metric in DECLARED["mine"]:
        assert Metric.declared(metric.name, metric.describe()) == metric

"""A summary's per-scorer path (``row_metric_flat``) gives each row the value the one rule
(``metric_value``) gives, whatever the declaration: two ways to compute one value must agree."""

from __future__ import annotations

import itertools
from types import SimpleNamespace

from povagent.scoring.metrics import Metric, metric_value, row_metric_flat

FIELD_VALUES = [None, True, False, 0, 1, 0.25, float("nan"), float("inf"), "x"]


def metrics() -> list[Metric]:
    out = []
    for k, (aggregation, over, negate, unscored) in enumerate(
        itertools.product(["mean", "rate"], ["answered", "all"], [False, True], [None, 0.0])
    ):
        out.append(Metric(name=f"m{k}", better="higher", aggregation=aggregation, field="v", label="m", caption="m",
                          over=over, negate=negate, unscored=unscored))  # fmt: skip
    return out


def test_the_per_scorer_path_gives_what_the_one_rule_gives_for_every_declaration_and_row():
    declared = {"s": metrics()}
    for status, fields in itertools.product(
        ["answered", "unanswered"],
        [None, {"answered": False}] + [{"v": v} for v in FIELD_VALUES] + [{"answered": True, "v": v} for v in FIELD_VALUES],
    ):
        row = SimpleNamespace(status=status, scores={"s": fields} if fields is not None else {})
        expected = [metric_value(m, fields, status == "answered") for m in declared["s"]]
        got = row_metric_flat(row, declared)
        assert [repr(v) for v in got] == [repr(v) for v in expected], (status, fields)

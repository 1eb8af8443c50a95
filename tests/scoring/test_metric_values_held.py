"""A row's declared metrics' values, as a report holds them: one small object a row, read as
``{scorer: {metric: value}}``, and made again the same when copied."""

from __future__ import annotations

import copy
import gc
import pickle
import sys

from povagent.scoring.metrics import Metric, MetricValues

DECLARED = {
    "mine": (Metric("error", "lower", "mean", "err", "Error", "mean error"), Metric("hit", "higher", "rate", "hit", "Hit", "hits")),
    "theirs": (Metric("score", "higher", "mean", "score", "Score", "mean score"),),
}


def test_the_values_read_as_each_scorers_metrics():
    values = MetricValues([0.25, None, 1.0], DECLARED)
    assert values == {"mine": {"error": 0.25, "hit": None}, "theirs": {"score": 1.0}}
    assert values.flat == (0.25, None, 1.0) and list(values) == ["mine", "theirs"]


def test_a_row_holds_a_pointer_a_value_and_no_more():
    error = 0.25
    values = MetricValues([error, None, 1.0], DECLARED)
    assert sys.getsizeof(values) <= sys.getsizeof(object()) + 16 + 3 * 8  # its header (and the collector's), one slot a value
    held = [r for r in gc.get_referents(values) if not isinstance(r, type)]
    assert len(held) == 3 and any(r is error for r in held)  # the values themselves: no tuple or dict of its own


def test_copied_values_are_the_same_values():
    values = MetricValues([0.25, None, 1.0], DECLARED)
    assert pickle.loads(pickle.dumps(values)) == values == copy.deepcopy(values)
    assert type(pickle.loads(pickle.dumps(values))) is type(values)

"""Mean relative accuracy as VSI-Bench's code computes it: numpy's linspace of
``int((.95 - .5) / .05 + 2)`` points, which is int(10.999999999999998) = 10 thresholds (not the
11 the formula reads as on paper), each MRA below counted by hand over the margins spelled out."""

from __future__ import annotations

import math

import pytest

from povagent.scoring.relative_accuracy import absolute_error, mean_relative_accuracy, mra_thresholds, relative_error

#: The thresholds θ spelled out (0.50 to 0.95 in steps of 0.05: the paper's C), and the relative
#: error each allows, 1 - θ, as float64 makes them (0.1 is 0.10000000000000009, 0.05 is
#: 0.050000000000000044).
THETAS = (0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95)
MARGINS = (0.5, 0.44999999999999996, 0.4, 0.35, 0.30000000000000004, 0.25, 0.19999999999999996,
           0.15000000000000002, 0.10000000000000009, 0.050000000000000044)  # fmt: skip


def test_the_threshold_count_is_int_of_a_float_just_short_of_eleven():
    assert (0.95 - 0.5) / 0.05 + 2 == 10.999999999999998
    assert len(mra_thresholds()) == 10
    assert mra_thresholds() == pytest.approx(THETAS, abs=1e-12)


@pytest.mark.parametrize(
    ("prediction", "gold", "within", "why"),
    [
        (3.0, 3.0, 10, "exact: within every margin"),
        (5.3, 5.0, 9, "error 0.06: within 0.1, not within 0.05"),
        (1.1, 1.0, 9, "error 0.10000000000000009: exactly the 0.9 margin's float, so within it"),
        (3.5, 5.0, 5, "error 0.3: within 0.30000000000000004, not within 0.25"),
        (1.45, 1.0, 2, "error 0.44999999999999996: exactly the 0.55 margin's float"),
        (2.0, 4.0, 1, "error 0.5: only the first margin, 0.5 itself"),
        (7.0, 4.0, 0, "error 0.75: within none"),
        (0.0, 2.0, 0, "error 1: within none"),
    ],
)
def test_mra_is_the_share_of_the_ten_margins_the_relative_error_is_within(prediction, gold, within, why):
    error = abs(prediction - gold) / gold
    assert sum(error <= m for m in MARGINS) == within, why  # the hand count over the margins above
    assert mean_relative_accuracy(prediction, gold) == within / 10


def test_an_error_on_the_last_margin_counts_as_numpy_counts_it():
    # 1 - 0.95 is 0.050000000000000044 in float64, and |1.05 - 1| is that same float: within
    assert mean_relative_accuracy(1.05, 1.0) == 1.0


def test_a_nan_or_infinite_prediction_is_accurate_at_no_threshold():
    assert mean_relative_accuracy(math.nan, 2.0) == 0.0
    assert mean_relative_accuracy(math.inf, 2.0) == 0.0


def test_a_gold_of_zero_has_no_relative_error():
    with pytest.raises(ZeroDivisionError):
        mean_relative_accuracy(1.0, 0.0)


def test_absolute_and_relative_error():
    assert absolute_error(2.5, 4.0) == 1.5
    assert relative_error(2.5, 4.0) == 0.375
    assert relative_error(6.0, 4.0) == 0.5

"""How close a number is to the gold number: mean relative accuracy, absolute and relative error.

Mean relative accuracy (MRA) is VSI-Bench's metric for its numerical-answer questions (Yang et
al., "Thinking in Space", 2024; ``mean_relative_accuracy`` of ``lmms_eval/tasks/vsibench/utils.py``
at vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8, the same function in
lmms-eval @ 75571cfe). A prediction is accurate at confidence ``θ`` when its relative error
``|pred - gold| / gold`` is at most ``1 - θ``; MRA is the share of the thresholds ``θ`` at which it
is. The thresholds are numpy's ``linspace(start, end, int((end - start) / interval + 2))``. For
``(.5, .95, .05)`` the count is ``int(10.999999999999998)``: in float64 ``.95 - .5`` is
0.44999999999999996, so the count is **10** (0.50, 0.55, ..., 0.95: the paper's set
``C = {0.5, 0.55, ..., 0.95}``), not the 11 the formula reads as on paper. Both the count and
numpy's float values of ``1 - θ`` are reproduced here, so a relative error that sits exactly on a
threshold counts as the official code counts it.

Pure: numbers in, numbers out; nothing here knows a set or a row.
"""

from __future__ import annotations

import math

import numpy as np

#: VSI-Bench's MRA range: ``start=.5, end=.95, interval=.05``.
MRA_START, MRA_END, MRA_INTERVAL = 0.5, 0.95, 0.05


def mra_thresholds(start: float = MRA_START, end: float = MRA_END, interval: float = MRA_INTERVAL) -> tuple[float, ...]:
    """The confidence thresholds θ the official code averages over (module docstring): 10 for
    VSI-Bench's defaults."""
    # the official count: int() of a float that falls just short of 11 for (.5, .95, .05), so 10
    count = int((end - start) / interval + 2)
    return tuple(float(t) for t in np.linspace(start, end, count))


def absolute_error(prediction: float, gold: float) -> float:
    """``|prediction - gold|``."""
    return abs(prediction - gold)


def relative_error(prediction: float, gold: float) -> float:
    """``|prediction - gold| / gold``, the official ``abs_dist_norm`` (divided by the gold value
    itself, not its magnitude). A gold of 0 has no relative error: :class:`ZeroDivisionError`,
    as in the official code."""
    return abs(prediction - gold) / gold


def mean_relative_accuracy(
    prediction: float, gold: float, start: float = MRA_START, end: float = MRA_END, interval: float = MRA_INTERVAL
) -> float:
    """The share of the thresholds θ (:func:`mra_thresholds`) at which ``relative_error <= 1 - θ``.

    A NaN or infinite prediction is accurate at no threshold (0.0), as numpy's comparison makes
    it officially. A gold of 0 raises :class:`ZeroDivisionError` (the official code crashes on it;
    VSI-Bench has none)."""
    return accuracy_over_thresholds(relative_error(prediction, gold), start, end, interval)


def accuracy_over_thresholds(error: float, start: float = MRA_START, end: float = MRA_END, interval: float = MRA_INTERVAL) -> float:
    """The share of the thresholds θ (:func:`mra_thresholds`) at which ``error <= 1 - θ``: the
    mean relative accuracy of a relative error however a harness computes it (VLMEvalKit's
    ``abs_dist_norm`` differs from the official one for a gold of 0 or below). NaN meets none."""
    if math.isnan(error):
        return 0.0
    # 1 - linspace(...) in numpy's float64, element by element, as the official comparison makes it
    margins = 1 - np.array(mra_thresholds(start, end, interval))
    return float(np.mean(error <= margins))

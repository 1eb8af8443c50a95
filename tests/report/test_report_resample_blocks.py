"""A report's bootstrap counts are filled a block of resamples at a time: the same counts as one
matrix of draws, and no more memory than the counts themselves."""

import tracemalloc

import numpy as np

from povagent.report.statistics import _resample_counts


def test_the_counts_are_those_of_one_matrix_of_draws():
    n_inst, n_boot = 2_500, 300
    draws = np.random.default_rng(3).integers(0, n_inst, size=(n_boot, n_inst))
    expected = np.stack([np.bincount(d, minlength=n_inst) for d in draws]).astype(float)
    assert np.array_equal(_resample_counts(n_inst, n_boot, 3), expected)


def test_filling_the_counts_costs_little_more_than_the_counts():
    n_inst, n_boot = 2_500, 2_000
    counts_bytes = n_inst * n_boot * 8
    tracemalloc.start()
    try:
        counts = _resample_counts(n_inst, n_boot, 0)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert counts.sum() == n_inst * n_boot
    assert peak < counts_bytes * 1.3  # draws, offsets and bincount of the whole matrix: 4x

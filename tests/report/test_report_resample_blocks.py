"""A report's bootstrap counts come a block of resamples at a time: the counts of one matrix of
draws, never the whole matrix at once."""

import tracemalloc

import numpy as np

from povagent.report.statistics import _resample_counts


def test_the_counts_are_those_of_one_matrix_of_draws():
    n_inst, n_boot = 2_500, 300
    draws = np.random.default_rng(3).integers(0, n_inst, size=(n_boot, n_inst))
    expected = np.stack([np.bincount(d, minlength=n_inst) for d in draws]).astype(float)
    blocks = list(_resample_counts(n_inst, n_boot, 3))
    assert len(blocks) > 1 and np.array_equal(np.concatenate(blocks), expected)


def test_the_counts_of_many_instances_never_take_the_memory_of_the_whole_matrix():
    n_inst, n_boot = 2_500, 4_000
    counts_bytes = n_inst * n_boot * 8
    tracemalloc.start()
    try:
        drawn = sum(int(block.sum()) for block in _resample_counts(n_inst, n_boot, 0))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert drawn == n_inst * n_boot
    assert peak < counts_bytes / 6  # a few blocks' worth; the whole matrix with its draws, offsets and bincount: 4x

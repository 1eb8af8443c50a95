"""The bootstrap resamples in blocks: the same draws as one matrix, memory bounded whatever n."""

import tracemalloc

import numpy as np

from povagent.scoring.bootstrap import DRAWS_PER_BLOCK, bootstrap_mean_ci, resample_draws


def test_the_blocks_hold_the_draws_of_one_matrix():
    n = DRAWS_PER_BLOCK // 3 + 7  # blocks of 3 resamples that do not divide n_boot
    blocks = list(resample_draws(n, 10, seed=5))
    assert len(blocks) > 1
    assert np.array_equal(np.concatenate(blocks), np.random.default_rng(5).integers(0, n, size=(10, n)))


def test_a_bootstrap_of_many_values_holds_one_block_of_draws_at_a_time():
    values = np.linspace(0.0, 1.0, 20_000)
    tracemalloc.start()
    try:
        estimate = bootstrap_mean_ci(values, n_boot=2000)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert estimate.n == 20_000 and estimate.lo < 0.5 < estimate.hi
    assert peak < 8 * 1024 * 1024  # one (2,000 x 20,000) matrix of draws would be 320 MB

"""The bootstrap resamples in blocks: the same draws as one matrix, memory bounded whatever n."""

import tracemalloc

import numpy as np

from povagent.scoring.bootstrap import DRAWS_PER_BLOCK, EMPTY, Estimate, bootstrap_mean_ci, bootstrap_mean_cis, resample_draws


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


def test_columns_bootstrapped_together_get_each_its_own_estimate_to_the_bit():
    rng = np.random.default_rng(3)
    columns = [
        rng.random(500),
        rng.random(500) * 2,  # as many values: the same draws
        np.where(rng.random(700) < 0.2, np.nan, rng.random(700)),  # NaNs dropped: its own count
        [0.25],  # one value: no interval
        [],  # none: no estimate
        [float("nan"), 1.0, 0.0],
    ]
    together = bootstrap_mean_cis(columns, n_boot=300, seed=7)
    assert together == [alone(c, n_boot=300, seed=7) for c in columns]
    assert together[3] == Estimate(0.25, None, None, 1) and together[4] is EMPTY
    assert bootstrap_mean_ci(columns[2], n_boot=300, seed=7) == together[2]


def alone(values, n_boot: int, seed: int) -> Estimate:
    """One column's estimate as the rule states it: the mean of its finite values, and the
    (1 - 0.95) / 2 and 1 - (1 - 0.95) / 2 quantiles of the means of ``n_boot`` resamples drawn
    with ``seed``."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return EMPTY
    if x.size < 2:
        return Estimate(float(x.sum() / x.size), None, None, int(x.size))
    means = np.concatenate([x[d].sum(axis=1) for d in resample_draws(x.size, n_boot, seed)]) / x.size
    alpha = (1.0 - 0.95) / 2.0
    lo, hi = np.quantile(means, [alpha, 1.0 - alpha])
    return Estimate(float(x.sum() / x.size), float(lo), float(hi), int(x.size))


def test_columns_of_0s_and_1s_constants_and_repeats_get_the_rules_estimate_to_the_bit():
    rng = np.random.default_rng(11)
    l2 = rng.random(400)
    hits = (rng.random(400) < 0.3).astype(float)
    columns = [
        l2, hits, np.ones(400), np.zeros(400), l2.copy(), hits.copy(),  # repeats share their twin's resamples
        -np.zeros(400), np.r_[-0.0, np.zeros(399)],  # -0.0 is not a plain 0: summed as the rule sums it
        rng.integers(0, 3, 400).astype(float),  # whole numbers, not only 0 and 1
    ]  # fmt: skip
    together = bootstrap_mean_cis(columns, n_boot=300, seed=2)
    assert [repr(e) for e in together] == [repr(alone(c, n_boot=300, seed=2)) for c in columns]


def test_smaller_blocks_give_the_same_estimates_to_the_bit():
    rng = np.random.default_rng(11)
    columns = [rng.random(3000), (rng.random(3000) < 0.4).astype(float), np.where(rng.random(3000) < 0.1, np.nan, rng.random(3000))]
    assert bootstrap_mean_cis(columns, n_boot=500, seed=2, per_block_draws=DRAWS_PER_BLOCK // 7) == bootstrap_mean_cis(columns, n_boot=500, seed=2)

"""Means over runs, bootstrap CIs and paired comparisons (povagent/report/statistics.py)."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.report.collect import Observation
from povagent.report.statistics import cell_stats, paired_comparison, sign_test_p
from povagent.scoring.bootstrap import bootstrap_mean_ci


def obs(instance: str, l2: float | None, run: int = 0, system: str = "s", in_frame: bool = True) -> Observation:
    answered = l2 is not None
    return Observation(
        system=system, run_name="r", run=run, instance_id=instance, house_id="h", pair_id="0", direction="left",
        condition="a", status="answered" if answered else "parse_error", parse_status="ok" if answered else "unparseable",
        answered=answered, l2=l2, l2_strict=l2, gt_in_frame=in_frame if answered else None, gt_behind=False if answered else None,
        gt_u=0.5, gt_v=0.5, selected_image=0, image_path=None, x=1.0, y=1.0, sentence="", raw=None,
    )


def test_bootstrap_ci_covers_the_true_mean_in_about_95_percent_of_seeds():
    true_mean, hits, trials = 0.3, 0, 300
    for seed in range(trials):
        rng = np.random.default_rng(seed)
        sample = rng.exponential(true_mean, size=120)  # skewed, like L2 errors
        est = bootstrap_mean_ci(sample, n_boot=600, seed=seed + 10_000)
        hits += est.lo <= true_mean <= est.hi
    assert 0.91 <= hits / trials <= 0.985


@pytest.mark.parametrize(("n", "n_boot"), [(1, 2000), (2, 2000), (37, 500), (800, 2000), (300, 0)])
def test_the_mean_interval_is_the_one_every_other_interval_is_drawn_from(n, n_boot):
    # the same resamples as the count-matrix machinery of every cell (same seed, same draws)
    from povagent.report.statistics import _ratio_estimates

    x = np.random.default_rng(n).exponential(0.3, size=n)
    fast = bootstrap_mean_ci(x, n_boot=n_boot, seed=5)
    (general,) = _ratio_estimates([(x[:, None], np.ones((n, 1)))], n_boot, 0.95, 5)
    assert fast.n == general.n and fast.value == pytest.approx(general.value, abs=1e-12)
    if general.lo is None:
        assert fast.lo is None and fast.hi is None
    else:
        assert fast.lo == pytest.approx(general.lo, abs=1e-12) and fast.hi == pytest.approx(general.hi, abs=1e-12)


def test_ci_narrows_as_instances_grow():
    rng = np.random.default_rng(0)
    small = bootstrap_mean_ci(rng.normal(0, 1, 50), n_boot=500)
    large = bootstrap_mean_ci(rng.normal(0, 1, 5000), n_boot=500)
    assert (large.hi - large.lo) < (small.hi - small.lo) / 5


def test_mean_over_runs_is_the_mean_of_each_runs_answered_mean():
    rows = [obs("i1", 0.1, 0), obs("i2", 0.3, 0), obs("i1", 0.5, 1), obs("i2", None, 1)]
    s = cell_stats(rows, n_boot=0)
    assert s.official.value == pytest.approx(((0.1 + 0.3) / 2 + 0.5) / 2)
    assert s.response_rate.value == pytest.approx((1.0 + 0.5) / 2)


def test_counting_non_responses_scores_an_unanswered_instance_as_the_center_guess():
    rows = [obs("i1", 0.1), obs("i2", None)]
    s = cell_stats(rows, fill={"i1": 0.9, "i2": 0.7}, n_boot=0)
    assert s.official.value == pytest.approx(0.1)
    assert s.counted.value == pytest.approx((0.1 + 0.7) / 2)


def test_counting_non_responses_is_absent_without_the_center_scores():
    assert cell_stats([obs("i1", 0.1), obs("i2", None)], n_boot=0).counted.value is None


def test_gt_in_selected_frame_is_a_share_of_answered_rows():
    rows = [obs("i1", 0.1, in_frame=True), obs("i2", 0.2, in_frame=False), obs("i3", None)]
    assert cell_stats(rows, n_boot=0).in_frame.value == pytest.approx(0.5)


def test_paired_comparison_detects_a_consistent_improvement():
    rng = np.random.default_rng(3)
    a = rng.uniform(0.2, 0.6, 80)
    b = a - 0.05 + rng.normal(0, 0.02, 80)
    c = paired_comparison("A", [obs(f"i{k}", v, system="A") for k, v in enumerate(a)], "B", [obs(f"i{k}", v, system="B") for k, v in enumerate(b)], n_boot=500)
    assert c.n_pairs == 80
    assert c.diff.hi < 0 and c.diff.value == pytest.approx(float(np.mean(b - a)))
    assert c.wilcoxon_p < 1e-6 and c.sign_p < 1e-6


def test_paired_comparison_uses_only_instances_both_answered():
    a = [obs("i1", 0.2, system="A"), obs("i2", 0.4, system="A"), obs("i3", None, system="A")]
    b = [obs("i1", 0.1, system="B"), obs("i2", None, system="B"), obs("i3", 0.3, system="B")]
    c = paired_comparison("A", a, "B", b, n_boot=100)
    assert c.n_pairs == 1 and c.diff.value == pytest.approx(-0.1)


def test_identical_systems_tie_everywhere_and_have_no_test():
    a = [obs(f"i{k}", 0.1 * k, system="A") for k in range(5)]
    c = paired_comparison("A", a, "B", a, n_boot=100)
    assert c.ties == 5 and c.diff.value == 0 and c.wilcoxon_p is None and c.sign_p is None


@pytest.mark.parametrize(
    ("pos", "neg", "p"),
    [
        (0, 1, 1.0),  # one instance can show nothing
        (5, 0, 2 / 32),  # all five one way: 2 * (1/2)^5
        (0, 5, 2 / 32),  # two-sided: the same the other way
        (3, 3, 1.0),
        (1, 5, 2 * 7 / 64),  # P(<= 1 of 6) = (1 + 6) / 64, doubled
    ],
)
def test_sign_test_is_the_exact_two_sided_binomial_test(pos, neg, p):
    assert sign_test_p(pos, neg) == pytest.approx(p, rel=1e-12)


def test_sign_test_has_no_p_value_without_a_difference():
    assert sign_test_p(0, 0) is None


def test_ci_of_a_multi_run_mean_with_non_responses_covers_the_true_mean_in_about_95_percent_of_seeds():
    # what a report's cells are: instances of varying difficulty, three runs that agree on the
    # hard ones (errors scattered around the instance's difficulty), 20% non-responses; the true
    # answered mean is the mean difficulty. (Resampling rows instead of instances covers far
    # less often: the runs of one instance are not independent evidence.)
    true_mean, hits, trials, n_inst, runs = 0.3, 0, 200, 120, 3
    for seed in range(trials):
        rng = np.random.default_rng(seed)
        difficulty = rng.gamma(4.0, true_mean / 4.0, n_inst)
        rows = []
        for i, d in enumerate(difficulty):
            for r in range(runs):
                answered = rng.random() < 0.8
                l2 = float(d * rng.lognormal(-0.02, 0.2)) if answered else None  # mean-preserving noise
                rows.append(obs(f"i{i}", l2, run=r))
        est = cell_stats(rows, n_boot=400, seed=seed).official
        hits += est.lo <= true_mean <= est.hi
    assert 0.90 <= hits / trials <= 0.985

"""Statistics of a report: means over runs with bootstrap CIs, and paired comparisons.

Every mean in a report has the form "for each run, a ratio of sums over instances; then the
mean over runs": the official error is sum(l2 over answered) / #answered, the response rate is
#answered / #rows, the share of GT in the selected frame is #in-frame / #answered, and on a real-world set the success
rate is #hits / #rows (an unanswered row is a failure, as the paper counts it). A single run's
value is therefore exactly the scorer's. Confidence intervals are percentile bootstrap
intervals that resample *instances* (all runs of an instance move together, so run-to-run
agreement on an instance is not mistaken for independent evidence).

Paired comparisons of two systems use the instances both answered (per-instance errors averaged
over runs): the mean difference with a bootstrap CI, the Wilcoxon signed-rank test and the exact
sign test. On success (per-instance hit rate over runs) every instance counts, answered or not,
and higher is better.

Pure numerics: nothing here reads files or knows about tables.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass
from typing import Iterable, Iterator, Literal, Mapping

import numpy as np

from povagent.report.collect import Observation
from povagent.scoring.bootstrap import CONFIDENCE, DEFAULT_BOOT, DRAWS_PER_BLOCK, EMPTY, Estimate, bootstrap_mean_ci, resample_draws


@dataclass
class InstanceMatrix:
    """One group's rows as (instance x run) arrays; a missing row is ``present = False``."""

    ids: list[str]
    runs: list[int]
    present: np.ndarray
    answered: np.ndarray
    l2: np.ndarray
    l2_strict: np.ndarray
    in_frame: np.ndarray
    fill: np.ndarray
    success: np.ndarray

    @property
    def n_instances(self) -> int:
        """Instances in the group."""
        return len(self.ids)


def instance_matrix(observations: Iterable[Observation], fill: Mapping[str, float] | None = None) -> InstanceMatrix:
    """Arrange observations by instance and run; ``fill`` maps instance id -> a non-response's score."""
    obs = list(observations)
    ids = sorted({o.instance_id for o in obs})
    runs = sorted({o.run for o in obs})
    ii = {k: i for i, k in enumerate(ids)}
    ri = {k: i for i, k in enumerate(runs)}
    shape = (len(ids), len(runs))
    present = np.zeros(shape, bool)
    answered = np.zeros(shape, bool)
    l2 = np.full(shape, np.nan)
    strict = np.full(shape, np.nan)
    in_frame = np.full(shape, np.nan)
    success = np.full(shape, np.nan)
    for o in obs:
        i, r = ii[o.instance_id], ri[o.run]
        present[i, r] = True
        if o.success is not None:
            success[i, r] = 1.0 if o.success else 0.0
        # a normalized_l2 row is answered with its error; any other row has no error to carry
        if o.answered and (o.l2 is not None or o.protocol != "normalized_l2"):
            answered[i, r] = True
            l2[i, r] = o.l2 if o.l2 is not None else np.nan
            strict[i, r] = o.l2_strict if o.l2_strict is not None else np.nan
            if o.gt_in_frame is not None:
                in_frame[i, r] = 1.0 if o.gt_in_frame else 0.0
    fill_arr = np.array([fill.get(k, np.nan) if fill else np.nan for k in ids], dtype=float)
    return InstanceMatrix(ids, runs, present, answered, l2, strict, in_frame, fill_arr, success)


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den elementwise, NaN where den is 0 (a run with nothing to average)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), np.nan)


def _mean_over_runs(per_run: np.ndarray) -> np.ndarray:
    ok = np.isfinite(per_run)
    cnt = ok.sum(axis=-1)
    s = np.where(ok, per_run, 0.0).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(cnt > 0, s / np.where(cnt > 0, cnt, 1), np.nan)


def _resample_counts(n_inst: int, n_boot: int, seed: int) -> Iterator[np.ndarray]:
    """How often each instance is drawn in each bootstrap resample: the rows of an
    (n_boot, n_inst) matrix, a block of resamples at a time
    (:func:`~povagent.scoring.bootstrap.resample_draws`), so a report's memory does not grow
    with the instances."""
    # half the shared block: a block's draws, bincount and counts are alive at once here
    for draws in resample_draws(n_inst, n_boot, seed, DRAWS_PER_BLOCK // 2):
        rows = draws.shape[0]
        # one bincount over (resample, instance) cells: much faster than numpy's multinomial
        # offset in place, and the draws let go before the block is used: one block's temporaries
        # at a time, not three
        draws += (np.arange(rows) * n_inst)[:, None]
        counts = np.bincount(draws.ravel(), minlength=rows * n_inst).reshape(rows, n_inst).astype(float)
        del draws
        yield counts


def _ratio_estimates(
    metrics: list[tuple[np.ndarray, np.ndarray]], n_boot: int, level: float, seed: int
) -> list[Estimate]:
    """For each (values, weights) pair: the mean over runs of per-run ratios, with an
    instance-resampling percentile bootstrap CI. One set of resamples serves every pair:
    a resample is a count per instance, so its sums are one matrix product (fast at 2,439
    instances x 2,000 resamples)."""
    n_inst = metrics[0][0].shape[0] if metrics else 0
    resampled = n_boot > 0 and n_inst >= 2
    alpha = (1.0 - level) / 2.0
    n_runs = metrics[0][0].shape[1] if metrics else 0
    # every metric's numerators and denominators side by side, written in place (one matrix,
    # not a copy of each pair): one matrix product per block of resamples sums them all
    columns = np.empty((n_inst, 2 * n_runs * len(metrics)))
    prepared = []
    for k, (values, weights) in enumerate(metrics):
        vw = columns[:, 2 * k * n_runs : (2 * k + 1) * n_runs]
        w = columns[:, (2 * k + 1) * n_runs : (2 * k + 2) * n_runs]
        w[...] = weights
        np.multiply(np.nan_to_num(values), w, out=vw)
        vw[w <= 0] = 0.0
        prepared.append((vw, w))
    sums = None
    if resampled and prepared:
        # every block's sums written into one matrix made first: a block's small product left
        # between its large temporaries would pin the heap above them, block after block
        sums = np.empty((n_boot, columns.shape[1]))
        start = 0
        for counts in _resample_counts(n_inst, n_boot, seed):
            _exact_order_product(counts, columns, out=sums[start : start + counts.shape[0]])
            start += counts.shape[0]
    out: list[Estimate] = []
    for k, (vw, weights) in enumerate(prepared):
        point = float(_mean_over_runs(_ratio(vw.sum(axis=0), weights.sum(axis=0))))
        n = int((weights.sum(axis=1) > 0).sum())
        if not math.isfinite(point):
            out.append(Estimate(None, None, None, n))
            continue
        if sums is None:
            out.append(Estimate(point, None, None, n))
            continue
        num = sums[:, 2 * k * n_runs : (2 * k + 1) * n_runs]
        den = sums[:, (2 * k + 1) * n_runs : (2 * k + 2) * n_runs]
        boot = _mean_over_runs(_ratio(num, den))
        boot = boot[np.isfinite(boot)]
        if boot.size == 0:
            out.append(Estimate(point, None, None, n))
            continue
        lo, hi = np.quantile(boot, [alpha, 1.0 - alpha])
        out.append(Estimate(point, float(lo), float(hi), n))
    return out


@dataclass(frozen=True)
class CellStats:
    """The numbers of one table cell group (a system on a subset of instances)."""

    n_instances: int
    n_runs: int
    official: Estimate
    response_rate: Estimate
    strict: Estimate
    counted: Estimate
    in_frame: Estimate
    behind: Estimate
    success: Estimate = EMPTY

    def as_dict(self) -> dict[str, object]:
        """JSON-able form."""
        return {
            "n_instances": self.n_instances,
            "n_runs": self.n_runs,
            "success_rate": self.success.as_dict(),
            "official_mean_l2": self.official.as_dict(),
            "response_rate": self.response_rate.as_dict(),
            "strict_mean_l2": self.strict.as_dict(),
            "counting_non_responses_mean_l2": self.counted.as_dict(),
            "gt_in_selected_frame": self.in_frame.as_dict(),
            "gt_behind_selected_camera": self.behind.as_dict(),
        }


def cell_stats(
    observations: Iterable[Observation],
    fill: Mapping[str, float] | None = None,
    n_boot: int = DEFAULT_BOOT,
    seed: int = 0,
) -> CellStats:
    """Official mean (answered only), response rate, strict mean, counting-non-responses mean
    (needs ``fill``), share of answered rows with the GT in the scored frame (on a real-world
    set: the selected frame carries a mark), share with the GT behind the scored camera, and
    the success rate (hits / all rows, real-world sets), each a mean over runs with a
    bootstrap CI; a statistic the rows do not carry is ``None``."""
    obs = list(observations)
    m = instance_matrix(obs, fill)
    behind = np.full(m.present.shape, np.nan)
    ii = {k: i for i, k in enumerate(m.ids)}
    ri = {k: i for i, k in enumerate(m.runs)}
    for o in obs:
        if o.answered and o.gt_behind is not None:
            behind[ii[o.instance_id], ri[o.run]] = 1.0 if o.gt_behind else 0.0
    ans = m.answered.astype(float)
    present = m.present.astype(float)
    metrics = [
        (m.l2, ans * np.isfinite(m.l2)),  # success rows are answered without an error
        (ans, present),
        (m.l2_strict, ans * np.isfinite(m.l2_strict)),
        (m.in_frame, ans * np.isfinite(m.in_frame)),
        (behind, np.isfinite(behind).astype(float)),
        (m.success, (m.present & np.isfinite(m.success)).astype(float)),
    ]
    with_counted = False
    if fill is not None and m.n_instances:
        filled = np.where(m.answered, m.l2, m.fill[:, None])
        if np.isfinite(filled[m.present]).all():
            metrics.append((filled, present))
            with_counted = True
    est = _ratio_estimates(metrics, n_boot, CONFIDENCE, seed)
    return CellStats(
        n_instances=m.n_instances,
        n_runs=len(m.runs),
        official=est[0],
        response_rate=est[1],
        strict=est[2],
        counted=est[6] if with_counted else EMPTY,
        in_frame=est[3],
        behind=est[4],
        success=est[5],
    )


@dataclass(frozen=True)
class PairedComparison:
    """System B against system A on the instances both answered (difference = B - A)."""

    a: str
    b: str
    metric: str
    n_pairs: int
    mean_a: float | None
    mean_b: float | None
    diff: Estimate
    wilcoxon_p: float | None
    sign_p: float | None
    b_better: int
    a_better: int
    ties: int

    def as_dict(self) -> dict[str, object]:
        """JSON-able form."""
        return {
            "a": self.a,
            "b": self.b,
            "metric": self.metric,
            "n_pairs": self.n_pairs,
            "mean_a": self.mean_a,
            "mean_b": self.mean_b,
            "mean_diff_b_minus_a": self.diff.as_dict(),
            "wilcoxon_p": self.wilcoxon_p,
            "sign_test_p": self.sign_p,
            "b_better": self.b_better,
            "a_better": self.a_better,
            "ties": self.ties,
        }


#: What a paired comparison compares per instance (:func:`per_instance_error`).
Compared = Literal["l2", "strict", "counted", "hit"]


def per_instance_error(
    observations: Iterable[Observation], metric: Compared = "l2", fill: Mapping[str, float] | None = None
) -> dict[str, float]:
    """Each instance's score averaged over runs: the error ``l2`` (answered runs only; an
    instance never answered is absent), ``strict``, or ``counted`` (non-responses scored by
    ``fill``); or ``hit``, the hit rate over every run (real-world sets; higher is better)."""
    sums: dict[str, list[float]] = defaultdict(list)
    for o in observations:
        if metric == "hit":
            v = None if o.success is None else float(o.success)
        elif metric == "counted":
            v = o.l2 if o.answered else (fill or {}).get(o.instance_id)
        elif metric == "strict":
            v = o.l2_strict if o.answered else None
        else:
            v = o.l2 if o.answered else None
        if v is not None and math.isfinite(v):
            sums[o.instance_id].append(float(v))
    return {k: sum(v) / len(v) for k, v in sums.items() if v}


#: Metrics of :func:`per_instance_error` where a larger value is the better one.
HIGHER_IS_BETTER = frozenset({"hit"})


def sign_test_p(n_pos: int, n_neg: int) -> float | None:
    """Exact two-sided sign test: P(as extreme a split | p = 1/2); ties are dropped before."""
    n = n_pos + n_neg
    if n == 0:
        return None
    from scipy.stats import binomtest  # scipy is heavy: only when a comparison is made

    return float(binomtest(n_pos, n, 0.5, alternative="two-sided").pvalue)


def paired_comparison(
    a_label: str,
    a_obs: Iterable[Observation],
    b_label: str,
    b_obs: Iterable[Observation],
    metric: Compared = "l2",
    fill: Mapping[str, float] | None = None,
    n_boot: int = DEFAULT_BOOT,
    seed: int = 0,
    label: str | None = None,
) -> PairedComparison:
    """Compare B with A on the same instances: mean difference (B - A) with CI, Wilcoxon
    signed-rank and exact sign tests. ``b_better`` counts instances where B's value is the
    better one: lower for errors, higher for ``hit``. ``label`` names the comparison's metric
    (default: ``metric``)."""
    ea = per_instance_error(a_obs, metric, fill)
    eb = per_instance_error(b_obs, metric, fill)
    common = sorted(set(ea) & set(eb))
    va = np.array([ea[k] for k in common])
    vb = np.array([eb[k] for k in common])
    d = vb - va
    # differences below float noise are ties (same answer scored twice)
    nz = d[np.abs(d) > 1e-12]
    wil = None
    if nz.size >= 1:
        from scipy.stats import wilcoxon  # scipy is heavy to import: only when comparing

        try:
            wil = float(wilcoxon(nz).pvalue)
        except ValueError:
            wil = None
    b_wins = nz > 0 if metric in HIGHER_IS_BETTER else nz < 0
    return PairedComparison(
        a=a_label,
        b=b_label,
        metric=label or metric,
        n_pairs=len(common),
        mean_a=float(va.mean()) if va.size else None,
        mean_b=float(vb.mean()) if vb.size else None,
        diff=bootstrap_mean_ci(d, n_boot=n_boot, seed=seed) if d.size else EMPTY,
        wilcoxon_p=wil,
        sign_p=sign_test_p(int((nz < 0).sum()), int((nz > 0).sum())),
        b_better=int(b_wins.sum()),
        a_better=int(nz.size - b_wins.sum()),
        ties=int(d.size - nz.size),
    )


def _exact_order_product(counts: np.ndarray, columns: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``counts @ columns`` summed in one fixed order on every machine.

    A BLAS matrix product picks its kernel by CPU and splits its sums by thread count, so the
    last bit of a CI would differ between machines (OpenBLAS's Haswell and Sandybridge kernels,
    or one thread and two, give different bits here). numpy's own ``einsum`` loop adds in the
    order the arrays are laid out, whatever the CPU or thread count."""
    return np.einsum("ij,jk->ik", counts, columns, optimize=False, out=out)

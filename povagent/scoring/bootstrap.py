"""A mean with its percentile bootstrap confidence interval: the one estimate that scoring
(the egocentric-bias index of :mod:`povagent.scoring.diagnostics_breakdown`) and the reports
(:mod:`povagent.report.statistics`) share.

Pure numerics at the bottom of the tree: nothing here reads files, and nothing here imports the
report or the run layers (the run summary and the report both reach down to it).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

#: Bootstrap resamples per interval; 2,000 keeps the 2.5/97.5 percentiles stable to ~0.001.
DEFAULT_BOOT = 2000
CONFIDENCE = 0.95
#: Draws held at once while resampling (2 MB of indices): a resample's draws are the same in
#: one block or in many (one generator, read in order), so memory stays flat at any row count.
DRAWS_PER_BLOCK = 1 << 18


@dataclass(frozen=True)
class Estimate:
    """A mean with its 95% bootstrap CI; ``value`` is ``None`` when nothing was measured."""

    value: float | None
    lo: float | None = None
    hi: float | None = None
    n: int = 0

    def as_dict(self) -> dict[str, float | int | None]:
        """JSON-able form."""
        return {"value": self.value, "ci_lo": self.lo, "ci_hi": self.hi, "n": self.n}


EMPTY = Estimate(None)


def bootstrap_mean_ci(
    values: Sequence[float] | np.ndarray, n_boot: int = DEFAULT_BOOT, level: float = CONFIDENCE, seed: int = 0
) -> Estimate:
    """Mean of ``values`` with a percentile bootstrap CI (resampling the values).

    The resamples are those of every other interval of a report
    (:func:`povagent.report.statistics._resample_counts`' draws, the same seed); a resample's mean
    is the mean of the values it drew, taken directly rather than through a count matrix (4x less
    CPU; the same interval as :func:`povagent.report.statistics._ratio_estimates` of the values with
    unit weights, to rounding)."""
    return bootstrap_mean_cis([values], n_boot, level, seed)[0]


def bootstrap_mean_cis(
    columns: Sequence[Sequence[float] | np.ndarray], n_boot: int = DEFAULT_BOOT, level: float = CONFIDENCE, seed: int = 0,
    per_block_draws: int = DRAWS_PER_BLOCK,
) -> list[Estimate]:
    """:func:`bootstrap_mean_ci` of each of ``columns``, the same estimates to the bit: columns
    with as many finite values share one pass over the draws (the draws depend only on that
    count and the seed), so a cell's several metrics draw their resamples once, not once each.
    ``per_block_draws``: at most as many draws at a time (:func:`resample_draws`; the same estimates)."""
    kept = [_finite(values) for values in columns]
    out: list[Estimate] = [EMPTY] * len(kept)
    by_size: dict[int, list[int]] = {}
    for k, x in enumerate(kept):
        n = int(x.size)
        if n == 0:
            continue
        out[k] = Estimate(float(x.sum() / n), None, None, n)
        if n_boot > 0 and n >= 2:
            by_size.setdefault(n, []).append(k)
    alpha = (1.0 - level) / 2.0
    for n, ks in by_size.items():
        resampled = _resampled(kept, ks, out)
        sums: list[list[np.ndarray]] = [[] for _ in resampled]
        for draws in resample_draws(n, n_boot, seed, per_block_draws) if resampled else ():
            for sink, (x, binary) in zip(sums, resampled.values(), strict=True):
                # a resample's sum of 0s and 1s is a count, exact in any order: the same
                # number as the float sum; ``take`` gathers as indexing does, faster
                sink.append(np.count_nonzero(x.take(draws), axis=1) if binary else x.take(draws).sum(axis=1))
        for sink, k in zip(sums, resampled, strict=True):
            lo, hi = np.quantile(np.concatenate(sink) / n, [alpha, 1.0 - alpha])
            out[k] = Estimate(out[k].value, float(lo), float(hi), n)
        for k in ks:
            if out[k].lo is None:  # the same values as an earlier column: its interval
                twin = next(j for j in resampled if _same(kept[j], kept[k]))
                out[k] = Estimate(out[k].value, out[twin].lo, out[twin].hi, n)
    return out


def _finite(values: Sequence[float] | np.ndarray) -> np.ndarray:
    """The finite values of a column, in order: the column itself when all are (no copy of a
    report's longest columns while their draws are summed)."""
    x = np.asarray(values, dtype=float)
    finite = np.isfinite(x)
    return x if finite.all() else x[finite]


def _resampled(kept: list[np.ndarray], ks: list[int], out: list[Estimate]) -> dict[int, tuple[np.ndarray, bool]]:
    """Which of the columns ``ks`` (as many values each) must be resampled, each with what is
    gathered and whether its values are all 0 or 1: a column equal to an earlier one is left
    out (its interval is that one's), and a column of 0s only or 1s only gets its interval in
    ``out`` now (every resample's mean is that value, exactly)."""
    resampled: dict[int, tuple[np.ndarray, bool]] = {}
    for k in ks:
        x = kept[k]
        if any(_same(kept[j], x) for j in resampled):
            continue
        # 0.0 and 1.0 only (not -0.0, whose sums may keep its sign)
        binary = bool(((x == 1.0) | ((x == 0.0) & ~np.signbit(x))).all())
        if binary and (x[0] == x).all():
            out[k] = Estimate(out[k].value, float(x[0]), float(x[0]), out[k].n)
            continue
        resampled[k] = (x.astype(bool) if binary else x, binary)
    return resampled


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two columns hold the same values, bit for bit."""
    return a.shape == b.shape and bool((a.view(np.uint64) == b.view(np.uint64)).all())


def resample_draws(n: int, n_boot: int, seed: int, per_block_draws: int = DRAWS_PER_BLOCK) -> Iterator[np.ndarray]:
    """The ``(n_boot, n)`` matrix of bootstrap draws (indices in ``[0, n)``, seeded with
    ``seed``), yielded a block of whole resamples at a time, at most :data:`DRAWS_PER_BLOCK`
    draws each (``per_block_draws``: fewer): the same numbers as one ``integers(0, n, size=(n_boot, n))`` call (the
    generator hands out its stream in order whatever the block), without holding them all."""
    rng = np.random.default_rng(seed)
    per_block = max(1, per_block_draws // max(n, 1))
    for start in range(0, n_boot, per_block):
        yield rng.integers(0, n, size=(min(per_block, n_boot - start), n))

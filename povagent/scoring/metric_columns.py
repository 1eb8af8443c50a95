"""Rows' values of the declared metrics, held in columns, and the one estimate of each metric.

A summary and a report both estimate a declared metric here (:func:`metric_slices`): the mean of
the values of the rows that count (a rate: of true values) with its 95% bootstrap CI, overall
and per slice (:func:`~povagent.scoring.breakdown.slices`). The rows are kept as
:class:`MetricColumns`: one array of doubles per metric (NaN where a row does not count:
:func:`~povagent.scoring.metrics.metric_value` never gives a value that is not finite) and each
row's slice labels, so a run's summary holds a few bytes per row and a slice is a set of
positions, not of objects. A slice's values are the column at its positions, in row order: the
same numbers, in the same order, as the rows' values.

Pure: nothing here reads files or knows a plugin.
"""

from __future__ import annotations

import sys
from array import array
from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from povagent.scoring.bootstrap import DEFAULT_BOOT, DRAWS_PER_BLOCK, Estimate, bootstrap_mean_cis
from povagent.scoring.breakdown import slices
from povagent.scoring.metrics import Declared, Metric, ValuedRow

_NAN = float("nan")


#: The category tuples met so far: one object per distinct tuple, however many rows carry it.
_TUPLES: dict[tuple[str, ...], tuple[str, ...]] = {}


def _label(value: Any) -> str | None:
    """A slice label as a row gives it, one string object per label however many rows carry it."""
    return None if value is None else sys.intern(str(value))


def _categories(value: Any) -> str | tuple[str, ...] | None:
    """A row's category label, or labels (a sub-category and its main category), shared objects."""
    if isinstance(value, tuple):
        labels = tuple(sys.intern(str(v)) for v in value)
        # a set has a few categories; a file with thousands is kept per row, not remembered
        return _TUPLES.setdefault(labels, labels) if len(_TUPLES) < 4096 else labels
    return _label(value)


class MetricColumns:
    """Rows' values of ``declared``'s metrics, a column per metric (scorer by scorer, each
    scorer's in its declared order), with each row's condition, direction, category (shared
    label strings: a pointer a row) and, for grouped metrics, its groups (kept for the rows that
    have any)."""

    __slots__ = ("declared", "_at", "_values", "_condition", "_direction", "_category", "_groups")

    def __init__(self, declared: Declared) -> None:
        self.declared: dict[str, tuple[Metric, ...]] = {s: tuple(ms) for s, ms in declared.items() if ms}
        self._at = {(s, m.name): i for i, (s, m) in enumerate((s, m) for s, ms in self.declared.items() for m in ms)}
        self._values = [array("d") for _ in self._at]
        self._condition: list[str | None] = []
        self._direction: list[str | None] = []
        self._category: list[str | tuple[str, ...] | None] = []
        self._groups: dict[int, Mapping[str, Mapping[str, str]]] = {}

    @classmethod
    def of(cls, rows: Iterable[ValuedRow], declared: Declared) -> MetricColumns:
        """The columns of ``rows``' values (what :func:`~povagent.scoring.metrics.valued_row` gives)."""
        columns = cls(declared)
        for row in rows:
            flat = [row.values.get(s, {}).get(m.name) for s, ms in columns.declared.items() for m in ms]
            columns.append(flat, row.condition, row.direction, row.category, row.groups)
        return columns

    def __len__(self) -> int:
        return len(self._condition)

    def append(
        self,
        flat: Sequence[float | None],
        condition: Any,
        direction: Any,
        category: str | tuple[str, ...] | None = None,
        groups: Mapping[str, Mapping[str, str]] | None = None,
    ) -> None:
        """One row: its values in the declared order (``None``: the row does not count), its
        slice labels, its category and its groups of grouped metrics."""
        for column, value in zip(self._values, flat, strict=True):
            column.append(_NAN if value is None else value)
        if groups:
            self._groups[len(self._condition)] = groups
        self._condition.append(_label(condition))
        self._direction.append(_label(direction))
        self._category.append(_categories(category))

    def taken(self, positions: np.ndarray) -> MetricColumns:
        """The rows at ``positions``, in that order, as columns of their own (compact)."""
        out = MetricColumns.__new__(MetricColumns)
        out.declared, out._at = self.declared, self._at
        out._values = [array("d", np.frombuffer(c, dtype=np.float64)[positions].tobytes()) if len(c) else array("d") for c in self._values]
        picked = positions.tolist()
        out._condition = [self._condition[i] for i in picked]
        out._direction = [self._direction[i] for i in picked]
        out._category = [self._category[i] for i in picked]
        new_position = {old: new for new, old in enumerate(picked) if old in self._groups} if self._groups else {}
        out._groups = {new: self._groups[old] for old, new in new_position.items()}
        return out

    def values(self, scorer: str, metric: Metric, rows: Sequence[int]) -> list[float] | np.ndarray:
        """What ``metric`` averages over the rows at positions ``rows``: each row's value (NaN:
        it does not count), or one value per group for a grouped metric (1.0 when every row of
        the group hit; a row with no group is a group of its own)."""
        column = self._values[self._at[(scorer, metric.name)]]
        if metric.group is None:
            if not len(column):
                return np.zeros(0)
            if rows == range(len(column)):  # every row (the overall cell): the column itself, not a copy
                return np.frombuffer(column, dtype=np.float64)
            at = np.fromiter(rows, dtype=np.int64, count=len(rows))
            return np.frombuffer(column, dtype=np.float64)[at]
        by_group: dict[Any, list[float]] = defaultdict(list)
        for n, i in enumerate(rows):
            value = column[i]
            if value == value:  # not NaN: the row counts
                by_group[self._groups.get(i, {}).get(scorer, {}).get(metric.name, ("row", n))].append(value)
        return [1.0 if all(v == 1.0 for v in values) else 0.0 for values in by_group.values()]

    def outside(self, rows: Sequence[int], categories: tuple[str, ...]) -> list[int]:
        """The positions of ``rows`` whose category (or main category) is none of ``categories``."""
        left_out = set(categories)
        kept = []
        for i in rows:
            label = self._category[i]
            labels = () if label is None else (label,) if isinstance(label, str) else label
            if left_out.isdisjoint(labels):
                kept.append(i)
        return kept

    def category_weighted(
        self, values: list[float] | np.ndarray, rows: Sequence[int], merged: tuple[tuple[str, ...], ...], only_whole: bool = False
    ) -> np.ndarray:
        """``values`` (one a row of ``rows``; NaN: not counted) rescaled so that their plain mean is
        the mean of the per-category means, the categories of each group in ``merged`` first
        averaged into one (:attr:`Metric.category_mean`): each counted row weighs
        ``1 / (units * categories in its unit * rows of its category)``. With ``only_whole`` a group
        merges only when each of its categories has counted rows. The bootstrap CI then
        resamples rows with those weights held fixed."""
        x = np.array(values, dtype=float)
        counted = [n for n in range(len(x)) if np.isfinite(x[n])]
        category = [self._category_name(rows[n]) for n in range(len(x))]
        per_category: dict[str, int] = defaultdict(int)
        for n in counted:
            per_category[category[n]] += 1
        whole = [group for group in merged if not only_whole or all(name in per_category for name in group)]
        unit_of = {name: group for group in whole for name in group}
        per_unit: dict[Any, set[str]] = defaultdict(set)
        for name in per_category:
            per_unit[unit_of.get(name, name)].add(name)
        for n in counted:
            unit = per_unit[unit_of.get(category[n], category[n])]
            x[n] *= len(counted) / (len(per_unit) * len(unit) * per_category[category[n]])
        return x

    def _category_name(self, i: int) -> str:
        label = self._category[i]
        return "" if label is None else label if isinstance(label, str) else label[0]

    def nbytes(self) -> int:
        """Bytes the columns hold (the values, and a pointer a label; groups not counted)."""
        return sum(8 * len(c) for c in self._values) + 24 * len(self)

    def slice_labels(self) -> tuple[Sequence[str | None], Sequence[str | None], Sequence[str | tuple[str, ...] | None] | None]:
        """Each row's condition, direction and category (``None`` when no row has a category)."""
        has_category = any(c is not None for c in self._category)
        return self._condition, self._direction, self._category if has_category else None


def metric_slices(
    columns: MetricColumns, scorer: str, n_boot: int = DEFAULT_BOOT, seed: int = 0, per_block_draws: int = DRAWS_PER_BLOCK
) -> dict[str, Any]:
    """Each of ``scorer``'s declared metrics over ``columns``' rows, overall and per slice
    (:func:`~povagent.scoring.breakdown.slices`: condition, direction, condition x direction,
    category): ``{metric: Estimate}`` a cell, each the mean of the values that count with its
    95% bootstrap CI (resampled with ``seed``) and the number of values counted."""
    metrics = columns.declared.get(scorer, ())
    condition, direction, category = columns.slice_labels()
    everything = range(len(columns))

    def counted(metric: Metric, rows: Sequence[int]) -> Sequence[int]:
        # only the overall cell (``slices`` hands it ``everything`` itself) leaves categories out
        return columns.outside(rows, metric.overall_excludes) if rows is everything and metric.overall_excludes else rows

    def values(metric: Metric, rows: Sequence[int]) -> list[float] | np.ndarray:
        kept = counted(metric, rows)
        found = columns.values(scorer, metric, kept)
        if rows is everything and metric.category_mean and metric.group is None:
            return columns.category_weighted(found, kept, metric.merged_categories, metric.merge_only_whole)
        return found

    # cells of as many rows are estimated in one call, filled in after: their columns share
    # their draws (the same estimates to the bit; a breakdown's cells often count as many rows,
    # 3 conditions x 4 runs), and only one such group's values are held at a time
    cells: list[tuple[Sequence[int], dict[str, Estimate]]] = []

    def cell(rows: Sequence[int]) -> dict[str, Estimate]:
        cells.append((rows, {}))
        return cells[-1][1]

    out = slices(
        everything,
        cell,
        condition=condition.__getitem__,
        direction=direction.__getitem__,
        category=None if category is None else category.__getitem__,
    )
    by_size: dict[int, list[tuple[Sequence[int], dict[str, Estimate]]]] = {}
    for rows, filled in cells:
        by_size.setdefault(len(rows), []).append((rows, filled))
    for group in by_size.values():
        wanted = [values(m, rows) for rows, _ in group for m in metrics]
        estimates = iter(bootstrap_mean_cis(wanted, n_boot=n_boot, seed=seed, per_block_draws=per_block_draws))
        for _, filled in group:
            filled.update((m.name, next(estimates)) for m in metrics)
    return out


def metrics_breakdown(valued: Iterable[ValuedRow] | MetricColumns, declared: Declared, n_boot: int = DEFAULT_BOOT) -> dict[str, dict[str, Any]]:
    """``summary.json``'s ``metrics`` section: per scorer, what it declared and, per slice, each
    metric's value with its 95% bootstrap CI and the number of rows it counts."""
    columns = valued if isinstance(valued, MetricColumns) else MetricColumns.of(valued, declared)
    out: dict[str, dict[str, Any]] = {}
    for scorer, metrics in columns.declared.items():
        by_slice = metric_slices(columns, scorer, n_boot)
        cells = {group: ({k: _as_dict(c) for k, c in v.items()} if group != "overall" else _as_dict(v)) for group, v in by_slice.items()}
        out[scorer] = {"declared": {m.name: m.describe() for m in metrics}, **cells}
    return out


def _as_dict(cell: Mapping[str, Estimate]) -> dict[str, Any]:
    return {name: e.as_dict() for name, e in cell.items()}

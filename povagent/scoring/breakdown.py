"""Summaries of scored rows: means over answered rows with the response rate beside each.

The official numbers: mean normalized L2 over answered instances only; response rate =
answered / total; share of answered rows whose GT lies in the scored frame. Broken down overall,
per condition, per direction and per condition x direction.

Several runs are aggregated as the paper aggregates them (the official ``run_all_eval.py``):
each run is summarized on its own, and a cell's number is the plain mean of the runs' numbers
(a run with nothing answered in the cell is left out of its mean). That is the default
everywhere a breakdown is shown. Pooling every row of every run into one mean weighs runs by
how many rows they answered and is *not* the paper's number: it stays available under the key
``pooled``, labelled so.

Conditions and directions are grouped by the label the rows carry, unknown labels included
(after the paper's, sorted), as the official scorer groups by the raw ``type``/``direction``.

Pure arithmetic: nothing here reads files or knows about tables.
"""

from __future__ import annotations

import math
from array import array
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from operator import attrgetter
from typing import Any, Callable, Iterable, Iterator, TypeVar, overload

from povagent.dataset.release_models import CONDITIONS, DIRECTIONS

T = TypeVar("T")
C = TypeVar("C")

#: The value of a breakdown's ``aggregation`` key: how its top-level cells combine runs.
PER_RUN_MEAN = "mean of per-run means"
#: The ``aggregation`` of a ``pooled`` breakdown: every row of every run in one mean.
POOLED = "pooled"

#: The cell fields that are per-run numbers, averaged over runs in a multi-run breakdown.
AVERAGED_FIELDS = ("response_rate", "mean_l2", "std_l2", "pct_in_frame", "mean_l2_strict", "mean_abs_x", "mean_abs_y")
#: The slice groups of a breakdown (each a mapping of label -> cell).
SLICE_GROUPS = ("per_condition", "per_direction", "per_condition_direction")


@dataclass(frozen=True, slots=True)
class ScoredRow:
    """The few fields a summary needs from a row; ``run`` is the run index it belongs to.

    ``condition`` and ``direction`` are group labels as the rows carry them (``None``: the row
    counts in ``overall`` only).
    """

    condition: str | None
    direction: str | None
    answered: bool
    l2: float | None
    gt_in_frame: bool | None
    l2_strict: float | None = None
    run: int = 0
    #: The official signed errors of an answered row (``None``: not recorded).
    error_x: float | None = None
    error_y: float | None = None
    #: The row carries a ``parse_error`` as the official runner would have written one.
    parse_error: bool = False
    #: The row answers a point question (POVBench's); a multiple-choice row is not counted
    #: here at all (its scorers' declared metrics say how it did), so a choice run's summary
    #: never claims its rows unanswered or misread by the official point reader.
    asks_point: bool = True


class Picked(Sequence[T]):
    """Some rows of a sequence, by position, each read when it is reached: a slice of a
    breakdown holds its rows' positions, not the rows, so rows kept in columns (a run summary's,
    :mod:`povagent.run.summary_table`) are built one at a time, and a list's rows are its own."""

    __slots__ = ("_rows", "_at")

    def __init__(self, rows: Sequence[T], at: array) -> None:
        if isinstance(rows, Picked):  # a slice of a slice: positions in the rows underneath
            under: Picked[T] = rows
            at, rows = array("q", (under._at[i] for i in at)), under._rows
        self._rows: Sequence[T] = rows
        self._at: array = at

    def __len__(self) -> int:
        return len(self._at)

    @overload
    def __getitem__(self, i: int) -> T: ...

    @overload
    def __getitem__(self, i: slice) -> Sequence[T]: ...

    def __getitem__(self, i: int | slice) -> T | Sequence[T]:
        if isinstance(i, slice):
            return Picked(self._rows, self._at[i])
        return self._rows[self._at[i]]

    def __iter__(self) -> Iterator[T]:
        rows = self._rows
        for i in self._at:
            yield rows[i]


def _positions() -> array:
    return array("q")


def _values() -> array:
    return array("d")


def summarize(rows: Iterable[ScoredRow]) -> dict[str, Any]:
    """One cell of one run (or of pooled rows): ``n`` (answered), ``n_total``,
    ``response_rate``, ``mean_l2``, ``std_l2`` (population std), ``pct_in_frame`` (percent of
    answered), ``mean_l2_strict``, the official ``mean_abs_x``/``mean_abs_y`` (mean absolute
    signed error over answered rows that record one) and ``n_parse_error`` (rows with a
    ``parse_error``, answered or not, as the official summary counts them).

    A NaN error (the official scorer records one for a NaN coordinate) makes the mean NaN, as
    the official mean is. Rows that ask no point (``asks_point`` false) are left out: a cell of
    a multiple-choice run's rows counts none (``n_total`` 0, no response rate).
    """
    # one pass over the rows; each mean is still ``sum()`` of its values in row order, the
    # values held unboxed (8 bytes each: a cell of every row of a run holds them all)
    errs = _values()
    strict = _values()
    abs_x = _values()
    abs_y = _values()
    total = in_frame = parse_errors = 0
    for r in rows:
        if not r.asks_point:
            continue
        total += 1
        if r.parse_error:
            parse_errors += 1
        if not r.answered or r.l2 is None:
            continue
        errs.append(r.l2)
        if r.gt_in_frame:
            in_frame += 1
        if r.l2_strict is not None:
            strict.append(r.l2_strict)
        if r.error_x is not None:
            abs_x.append(abs(r.error_x))
        if r.error_y is not None:
            abs_y.append(abs(r.error_y))
    n = len(errs)
    mean: float | None = None
    std: float | None = None
    if n:
        mean = sum(errs) / n
        std = math.sqrt(sum((e - mean) ** 2 for e in errs) / n)
    return {
        "n": n,
        "n_total": total,
        "response_rate": n / total if total else None,
        "mean_l2": mean,
        "std_l2": std,
        "pct_in_frame": 100.0 * in_frame / n if n else None,
        "mean_l2_strict": sum(strict) / len(strict) if strict else None,
        "mean_abs_x": sum(abs_x) / len(abs_x) if abs_x else None,
        "mean_abs_y": sum(abs_y) / len(abs_y) if abs_y else None,
        "n_parse_error": parse_errors,
    }


def _ordered(labels: Iterable[str], canonical: Iterable[str]) -> list[str]:
    """The paper's labels in the paper's order, then any other label, sorted."""
    present = set(labels)
    known = [c for c in canonical if c in present]
    return known + sorted(present - set(known), key=str)


def slices(
    rows: Iterable[T],
    cell: Callable[[Sequence[T]], C],
    condition: Callable[[T], str | None] = attrgetter("condition"),
    direction: Callable[[T], str | None] = attrgetter("direction"),
    category: Callable[[T], str | tuple[str, ...] | None] | None = None,
) -> dict[str, Any]:
    """The one breakdown: ``cell`` of all rows (``overall``), of each condition, each direction
    and each condition x direction. Every summary povagent shows (official means, success rates,
    a report's bootstrapped cells) is this grouping with its own ``cell``.

    A row without a condition (or direction; ``None`` or ``""``, as a multiple-choice set's item
    has none) counts overall only, as officially. Labels come in the paper's order, then any
    other label, sorted; only labels with rows appear. With ``category`` given and some row
    in a category (a multiple-choice question's type), ``per_category`` breaks the rows down
    by it too, labels sorted; a row whose ``category`` gives several labels (a sub-category and
    its main category) counts in each.

    A slice holds its rows' positions; ``cell`` gets it as a :class:`Picked` view of ``rows``
    (``overall``: ``rows`` itself, a sequence as handed in), so slicing keeps nothing per row
    but a position.
    """
    rows = rows if isinstance(rows, Sequence) else list(rows)
    by_c: dict[str, array] = defaultdict(_positions)
    by_d: dict[str, array] = defaultdict(_positions)
    by_cd: dict[tuple[str, str], array] = defaultdict(_positions)
    by_category: dict[str, array] = defaultdict(_positions)
    for i, r in enumerate(rows):
        c, d = condition(r), direction(r)
        if c:
            by_c[c].append(i)
        if d:
            by_d[d].append(i)
        if c and d:
            by_cd[(c, d)].append(i)
        if category is not None and (k := category(r)):
            for label in (k,) if isinstance(k, str) else k:
                by_category[label].append(i)
    c_order = _ordered(by_c, [str(c) for c in CONDITIONS])
    d_order = _ordered(by_d, [str(d) for d in DIRECTIONS])
    out = {
        "overall": cell(rows),
        "per_condition": {c: cell(Picked(rows, by_c[c])) for c in c_order},
        "per_direction": {d: cell(Picked(rows, by_d[d])) for d in d_order},
        "per_condition_direction": {
            f"{c}/{d}": cell(Picked(rows, by_cd[(c, d)])) for c in c_order for d in d_order if (c, d) in by_cd
        },
    }
    if by_category:  # only a run whose rows have categories says so: a POVBench summary is unchanged
        out["per_category"] = {k: cell(Picked(rows, by_category[k])) for k in sorted(by_category)}
    return out


def pooled_breakdown(rows: Iterable[ScoredRow]) -> dict[str, Any]:
    """Every row in one summary per slice, whatever its run (one run's breakdown, or the
    ``pooled`` variant of several)."""
    return slices(rows, summarize)


def _mean(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def mean_over_runs(cells: list[dict[str, Any]]) -> dict[str, Any]:
    """One cell from the same cell of several runs, as ``run_all_eval.py`` combines runs.

    Each of :data:`AVERAGED_FIELDS` is the plain mean of the runs' values, a run whose value is
    ``None`` (nothing answered, or no row, in this cell) left out; ``std_l2`` is thus the mean
    within-run spread. ``n`` and ``n_total`` are summed over runs; ``n_runs`` counts the runs
    with a row in the cell and ``run_mean_l2`` lists each run's mean.
    """
    out: dict[str, Any] = {
        "n": sum(c["n"] for c in cells),
        "n_total": sum(c["n_total"] for c in cells),
        "n_parse_error": sum(c.get("n_parse_error", 0) for c in cells),
    }
    for key in AVERAGED_FIELDS:
        out[key] = _mean([c[key] for c in cells if c.get(key) is not None])
    out["n_runs"] = sum(1 for c in cells if c["n_total"])
    out["run_mean_l2"] = [c["mean_l2"] for c in cells]
    return out


def breakdown(rows: Iterable[ScoredRow]) -> dict[str, Any]:
    """``overall``, ``per_condition``, ``per_direction`` and ``per_condition_direction``.

    With rows of one run, each cell summarizes that run. With several runs, each cell is the
    mean over runs of the run's own cell (:func:`mean_over_runs`, the paper's number), and the
    breakdown adds ``pooled`` (every row in one mean, labelled ``aggregation: "pooled"``) and
    ``per_run`` (each run's overall cell). ``aggregation`` and ``runs`` say which it is.
    ``n_parse_error`` (top level, as in the official summary) counts rows with a parse error,
    over every run.
    """
    rows = rows if isinstance(rows, Sequence) else list(rows)
    by_run: dict[int, array] = defaultdict(_positions)
    for i, r in enumerate(rows):
        by_run[r.run].append(i)
    runs = sorted(by_run)
    if len(runs) <= 1:
        single = pooled_breakdown(rows)
        single["aggregation"] = PER_RUN_MEAN if runs else POOLED
        single["runs"] = runs
        single["n_parse_error"] = single["overall"]["n_parse_error"]
        return single
    per_run = {run: pooled_breakdown(Picked(rows, by_run[run])) for run in runs}
    pooled = pooled_breakdown(rows)
    empty = summarize([])
    out: dict[str, Any] = {"overall": mean_over_runs([b["overall"] for b in per_run.values()])}
    for group in SLICE_GROUPS:
        # the pooled breakdown holds every label of every run, in order
        out[group] = {
            label: mean_over_runs([b[group].get(label, empty) for b in per_run.values()]) for label in pooled[group]
        }
    out["aggregation"] = PER_RUN_MEAN
    out["runs"] = runs
    out["pooled"] = {**pooled, "aggregation": POOLED}
    out["per_run"] = {str(run): b["overall"] for run, b in per_run.items()}
    out["n_parse_error"] = out["overall"]["n_parse_error"]
    return out

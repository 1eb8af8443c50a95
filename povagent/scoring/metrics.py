"""Metrics a scorer declares, and the one function that turns a row into their values.

A scorer says what its numbers mean (``Scorer.metrics``): each :class:`Metric` has a name, which
direction is better, how a row gives its value (a field of the scorer's scores, over the answered
rows or over every row), how values aggregate (``mean``, or ``rate`` of true values) and the words
a table shows (label, caption). The core never names a scorer: ``summary.json``'s ``metrics``
section, the console and the report render whatever was declared, per slice (overall, per
condition, per direction, per condition x direction: :func:`~povagent.scoring.breakdown.slices`),
each with its bootstrap CI (:func:`~povagent.scoring.bootstrap.bootstrap_mean_ci`), estimated
over rows' values kept in columns (:mod:`povagent.scoring.metric_columns`).

Pure: nothing here reads files or knows a plugin; a row is anything with ``status``, ``scores``,
``condition`` and ``direction``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any, ClassVar, Iterator, Literal, Sequence

#: Which way is better.
Better = Literal["lower", "higher"]
#: How row values aggregate: the mean of numbers, or the rate of true values.
Aggregation = Literal["mean", "rate"]


@dataclass(frozen=True)
class Metric:
    """One number a scorer declares.

    ``field`` is the key of the scorer's row scores the value is read from. ``over`` says which
    rows count: ``"answered"`` (rows the scorer scored as answered, e.g. a mean error) or
    ``"all"`` (every row; a row the scorer did not score, or scored unanswered, counts as
    false for a rate: a response rate, a success rate with non-responses as failures).
    ``negate`` counts a false value as the hit (a rate of ``gt_in_frame`` false, say).
    ``group`` is a regular expression that makes a metric a rate over groups of rows (a set's
    copies of one question): rows whose pair ids are equal once every match of it is removed
    form a group (``-flip`` pairs ``Q-2`` with ``Q-flip-2``), a hit only when every row of it
    is. The id is the row's own, so a row no scorer scored (an unreadable answer) still sinks
    its group; a run's rows group apart from another run's. ``overall_excludes`` names question
    categories whose rows the ``overall`` cell leaves out (MindCube's evaluator scores its
    ``translation`` setting on its own, outside the overall); their own slices keep them.
    ``unscored`` is the value of a mean over ``"all"`` rows for a row the scorer did not score
    (a reply its parser read nothing in): VSI-Bench scores such a reply 0 (its
    ``WORST_CASE_FOR_METRICS``), so its MRA counts it as 0, not as absent (``None``: absent).
    ``category_mean`` makes the ``overall`` cell the mean of the per-category means rather than
    the mean over rows (VSI-Bench's overall: each question type counts once, whatever its
    size), the categories of each group in ``merged_categories`` first averaged into one
    (VSI-Bench's three direction levels); the per-category cells are unchanged. A group merges
    even when some of its categories have no row, unless ``merge_only_whole`` is set: then it
    merges only when every one of them has rows, else each counts on its own (VLMEvalKit's
    ``VsiBench._aggregate``).
    ``select`` is a regular expression a row's pair id must contain (``re.search``) for the row
    to count at all: a metric over some of a set's copies (MMSI-Bench's circular evaluation
    reports its vanilla accuracy over each question's first copy alone); a row with no pair id
    does not count. ``None``: every row.
    """

    name: str
    better: Better
    aggregation: Aggregation
    field: str
    label: str
    caption: str
    over: Literal["answered", "all"] = "answered"
    negate: bool = False
    group: str | None = None
    overall_excludes: tuple[str, ...] = ()
    unscored: float | None = None
    category_mean: bool = False
    merged_categories: tuple[tuple[str, ...], ...] = ()
    merge_only_whole: bool = False
    select: str | None = None

    def describe(self) -> dict[str, Any]:
        """What ``summary.json`` says of the metric: enough to compute it again from rows
        (:meth:`declared`), so a report reads a third-party scorer's metrics without its plugin."""
        out = {
            "label": self.label,
            "caption": self.caption,
            "better": self.better,
            "aggregation": self.aggregation,
            "field": self.field,
            "over": self.over,
            "negate": self.negate,
        }
        if self.group is not None:  # said only when set: an ungrouped metric reads as it always did
            out["group"] = self.group
        if self.overall_excludes:
            out["overall_excludes"] = list(self.overall_excludes)
        if self.unscored is not None:
            out["unscored"] = self.unscored
        if self.category_mean:
            out["category_mean"] = True
            out["merged_categories"] = [list(group) for group in self.merged_categories]
            if self.merge_only_whole:  # said only when set: other metrics read as they always did
                out["merge_only_whole"] = True
        if self.select is not None:
            out["select"] = self.select
        return out

    @classmethod
    def declared(cls, name: str, description: Mapping[str, Any]) -> Metric:
        """The metric :meth:`describe` described."""
        return cls(
            name,
            description["better"],
            description["aggregation"],
            description["field"],
            description["label"],
            description["caption"],
            description["over"],
            description["negate"],
            description.get("group"),
            tuple(description.get("overall_excludes") or ()),
            description.get("unscored"),
            bool(description.get("category_mean")),
            tuple(tuple(g) for g in description.get("merged_categories") or ()),
            bool(description.get("merge_only_whole")),
            description.get("select"),
        )


#: Each scorer's declared metrics: ``{scorer: metrics}``.
Declared = Mapping[str, Sequence["Metric"]]


def metric_value(metric: Metric, fields: Mapping[str, Any] | None, answered: bool) -> float | None:
    """``metric``'s value for one row whose scorer wrote ``fields`` (``None``: not scored), or
    ``None`` when the row does not count for it."""
    return _value(metric, fields, _scored(fields, answered))


def _scored(fields: Mapping[str, Any] | None, answered: bool) -> bool:
    """Whether the row counts as scored by the scorer that wrote ``fields``."""
    # a plain dict told from other mappings first: the ABC check costs more than the rest
    return answered and (type(fields) is dict or isinstance(fields, Mapping)) and fields.get("answered", True) is True


def _value(metric: Metric, fields: Mapping[str, Any] | None, scored: bool) -> float | None:
    """:func:`metric_value` once :func:`_scored` is known (``fields`` is a mapping when it is)."""
    if metric.over == "answered" and not scored:
        return None
    if not scored and metric.unscored is not None and metric.aggregation == "mean":
        return metric.unscored
    raw = fields.get(metric.field) if scored else None  # type: ignore[union-attr]  # scored: a mapping
    if metric.aggregation == "rate":
        if raw is None and metric.over == "answered":
            return None
        hit = raw is True if not metric.negate else raw is False
        return 1.0 if hit else 0.0
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
        return None
    return float(raw)


def row_metric_values(row: Any, declared: Declared) -> dict[str, dict[str, float | None]]:
    """The one function turning a row into metric values: ``{scorer: {metric: value}}`` for every
    metric each scorer declared (see :func:`metric_value`)."""
    answered = str(getattr(row, "status", "")) == "answered"
    scores = getattr(row, "scores", None) or {}
    return {
        scorer: dict(zip((m.name for m in metrics), _selected(row, metrics, _scorer_values(metrics, scores.get(scorer), answered)), strict=True))
        for scorer, metrics in declared.items()
        if metrics
    }


def row_metric_flat(row: Any, declared: Declared) -> list[float | None]:
    """:func:`row_metric_values`' values alone, scorer by scorer in the declared order (what a
    summary's columns and :class:`MetricValues` keep)."""
    answered = str(getattr(row, "status", "")) == "answered"
    scores = getattr(row, "scores", None) or {}
    out: list[float | None] = []
    for scorer, metrics in declared.items():
        if metrics:
            selects, repeats = _facts(metrics)
            values = _scorer_values(metrics, scores.get(scorer), answered)
            if selects:
                values = _selected(row, metrics, values)
            if repeats:  # a name declared twice: its last value, once
                values = list(dict(zip((m.name for m in metrics), values)).values())
            out += values
    return out


#: :func:`_facts` of each scorer's metrics met so far, by the sequence's id (with the sequence,
#: so a reused id is told apart): a summary asks them of every row.
_FACTS: dict[int, tuple[Sequence[Metric], bool, bool]] = {}


def _facts(metrics: Sequence[Metric]) -> tuple[bool, bool]:
    """Whether any of ``metrics`` has a ``select``, and whether a name is declared twice."""
    known = _FACTS.get(id(metrics))
    if known is not None and known[0] is metrics:
        return known[1], known[2]
    selects = not all(m.select is None for m in metrics)
    repeats = len({m.name for m in metrics}) < len(metrics)
    if type(metrics) is not tuple:  # a list may change: only a tuple's facts are kept
        return selects, repeats
    if len(_FACTS) >= 1024:  # a few declarations a process: a flood of new ones is not kept
        _FACTS.clear()
    _FACTS[id(metrics)] = (metrics, selects, repeats)
    return selects, repeats


def _selected(row: Any, metrics: Sequence[Metric], values: list[float | None]) -> list[float | None]:
    """``values`` with ``None`` for each metric whose ``select`` the row's pair id does not meet."""
    if all(m.select is None for m in metrics):
        return values
    pair_id = getattr(row, "pair_id", None)
    return [
        None if m.select is not None and not (isinstance(pair_id, str) and re.search(m.select, pair_id)) else value
        for m, value in zip(metrics, values, strict=True)
    ]


def _scorer_values(metrics: Sequence[Metric], fields: Mapping[str, Any] | None, answered: bool) -> list[float | None]:
    """:func:`metric_value` of each of ``metrics`` for one scorer's ``fields``: whether the row
    counts is decided once for the scorer, not once a metric (a summary asks it of every row)."""
    scored = _scored(fields, answered)
    return [_value(metric, fields, scored) for metric in metrics]


def row_metric_groups(row: Any, declared: Declared) -> dict[str, dict[str, str]]:
    """``{scorer: {metric: group}}`` for every grouped metric: the row's pair id with every
    match of the metric's ``group`` removed, the run's index before it (a group never spans
    runs). Empty for a row with no pair id."""
    pair_id = getattr(row, "pair_id", None)
    if not isinstance(pair_id, str):
        return {}
    out: dict[str, dict[str, str]] = {}
    for scorer, metrics in declared.items():
        for m in metrics:
            if m.group is not None:
                out.setdefault(scorer, {})[m.name] = f"{getattr(row, 'run', 0)}#{re.sub(m.group, '', pair_id)}"
    return out


def row_category(row: Any) -> str | tuple[str, ...] | None:
    """The question's category, the slice a multiple-choice run breaks down by: the one the row
    records (``row.category``, written whatever the answer, so a reply naming no option counts
    in its slice as the wrong answer it is), with its main category where the row records one
    (``(category, main_category)``: the row counts in both slices); ``None``: none. (A row of
    an older format gets its category when it is read: :mod:`povagent.results.upgrade`.)"""
    recorded = getattr(row, "category", None)
    if not isinstance(recorded, str):
        return None
    main = getattr(row, "main_category", None)
    if isinstance(main, str) and main and main != recorded:
        return (recorded, main) if recorded else main
    return recorded or None


Names = tuple[tuple[str, tuple[str, ...]], ...]


class MetricValues(Mapping[str, Mapping[str, "float | None"]]):
    """A row's :func:`row_metric_values`, ``{scorer: {metric: value}}``, its values held in the
    slots of a class made once per declaration (:func:`_values_class`: the names and their
    positions are the class's, shared by every row): what a summary or a report keeps per row,
    one object of a pointer a value (80 bytes for six), without two dicts, nor a tuple beside it."""

    __slots__ = ()
    #: ``{scorer: {metric: position}}`` and the declaration's names, the class's own.
    _at: ClassVar[dict[str, dict[str, int]]] = {}
    _names: ClassVar[Names] = ()
    _slots: ClassVar[tuple[str, ...]] = ()

    def __new__(cls, flat: Sequence[float | None], declared: Declared) -> MetricValues:
        values = tuple(flat)
        names = tuple((scorer, tuple(m.name for m in metrics)) for scorer, metrics in declared.items() if metrics)
        return _values_class(names, len(values))._made(values)

    @classmethod
    def _made(cls, values: tuple[float | None, ...]) -> MetricValues:
        self = object.__new__(cls)
        for slot, value in zip(cls._slots, values, strict=True):
            object.__setattr__(self, slot, value)
        return self

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuilt, (self._names, self.flat)

    @classmethod
    def of(cls, row: Any, declared: Declared) -> MetricValues:
        """``row``'s values of the ``declared`` metrics (see :func:`row_metric_values`)."""
        return cls(row_metric_flat(row, declared), declared)

    @staticmethod
    def _flat_of(values: MetricValues) -> tuple[float | None, ...]:
        return ()  # a declaration's class gathers its slots

    @property
    def flat(self) -> tuple[float | None, ...]:
        """The values, scorer by scorer, each scorer's in its declared order."""
        return self._flat_of(self)

    def __getitem__(self, scorer: str) -> Mapping[str, float | None]:
        return _ScorerValues(self.flat, self._at[scorer])

    def __iter__(self) -> Iterator[str]:
        return iter(self._at)

    def __len__(self) -> int:
        return len(self._at)


#: The class of every declaration (and number of values) met so far: a few per process.
_CLASSES: dict[tuple[Names, int], type[MetricValues]] = {}


def _values_class(names: Names, count: int) -> type[MetricValues]:
    """The :class:`MetricValues` class of a declaration's ``names``, with a slot for each of ``count`` values."""
    made = _CLASSES.get((names, count))
    if made is None:
        at: dict[str, dict[str, int]] = {}
        i = 0
        for scorer, metric_names in names:
            at[scorer] = {name: i + k for k, name in enumerate(metric_names)}
            i += len(metric_names)
        slots = tuple(f"_{k}" for k in range(count))
        # the values as one tuple, gathered in C (one value: ``attrgetter`` gives it bare)
        flat_of = attrgetter(*slots) if count > 1 else (lambda self: (getattr(self, slots[0]),)) if count else (lambda self: ())
        body = {"__slots__": slots, "_slots": slots, "_at": at, "_names": names, "_flat_of": staticmethod(flat_of), "__module__": __name__}
        made = _CLASSES.setdefault((names, count), type("MetricValues", (MetricValues,), body))
    return made


def _rebuilt(names: Names, values: tuple[float | None, ...]) -> MetricValues:
    """A pickled :class:`MetricValues` made again (its class is made, not imported)."""
    return _values_class(names, len(values))._made(values)


class _ScorerValues(Mapping[str, "float | None"]):
    """One scorer's values of a :class:`MetricValues`."""

    __slots__ = ("_flat", "_at")

    def __init__(self, flat: tuple[float | None, ...], at: dict[str, int]) -> None:
        self._flat, self._at = flat, at

    def __getitem__(self, metric: str) -> float | None:
        return self._flat[self._at[metric]]

    def __iter__(self) -> Iterator[str]:
        return iter(self._at)

    def __len__(self) -> int:
        return len(self._at)


@dataclass(frozen=True, slots=True)
class ValuedRow:
    """A row as a metrics breakdown reads it: its slice labels, its metric values and the
    groups of its grouped metrics (small: a summary may keep one per key instead of the row)."""

    condition: str | None
    direction: str | None
    values: Mapping[str, Mapping[str, float | None]]
    category: str | tuple[str, ...] | None = None
    groups: Mapping[str, Mapping[str, str]] = field(default_factory=dict)


def valued_row(row: Any, declared: Declared) -> ValuedRow:
    """``row``'s slice labels, :func:`row_metric_values`, its category and its groups."""
    condition, direction = getattr(row, "condition", None), getattr(row, "direction", None)
    return ValuedRow(
        None if condition is None else str(condition),
        None if direction is None else str(direction),
        row_metric_values(row, declared),
        row_category(row),
        row_metric_groups(row, declared),
    )

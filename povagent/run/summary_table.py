"""What a summary reads of a run's rows, one row per key, kept in columns.

:class:`SummaryTable` takes rows one at a time (``results.jsonl`` read back, or rows in hand)
and keeps of each only the values ``summary.json`` is computed from, each field a
:class:`~povagent.run.row_columns.Column` (a byte a value, 9 for a number) and the declared metrics'
values a :class:`~povagent.scoring.metric_columns.MetricColumns`: under 200 bytes a row
whatever its text, where an object a row held several times that. Values that only some rows
have (a plugin scorer's fields, a diagnosis, a NaN coordinate's key) are kept by position for
those rows.

When a key repeats, its last row counts. The rows kept are read in one order whatever order
they came in: their keys' 128-bit BLAKE2b digests, ascending (the table keeps 16 bytes a row
instead of the key's text). A summary's sums and bootstrap draws follow the rows' order, so a
run whose rows were written as they finished, or over two sessions, a file read back and a
rescore of it all give one summary, to the last bit.

Its rows are read back as the objects the breakdowns take (:class:`ScoredRow`, and the like),
built one at a time as a breakdown reaches them (:class:`~povagent.scoring.breakdown.Picked`).
Nothing here reads a file or writes one.
"""

from __future__ import annotations

import hashlib
from array import array
from collections import Counter, defaultdict
from collections.abc import Container, Iterator, Mapping, Sequence
from operator import attrgetter
from typing import Any, overload

import numpy as np

from povagent.exchange.usage_totals import UsageTotals
from povagent.results.official_reading import holds_nan, official_view
from povagent.results.rows import STATUS_TEXT, ResultRow, RowStatus
from povagent.run.row_columns import Column
from povagent.run.summary_fields import diagnosed_row, plugin_scores, scored_values
from povagent.scoring.breakdown import Picked, ScoredRow
from povagent.scoring.diagnostics_breakdown import DiagnosedRow
from povagent.scoring.metric_columns import MetricColumns
from povagent.scoring.metrics import Declared, row_category, row_metric_flat, row_metric_groups
from povagent.scoring.score_protocols import diagnosing_scorers, registered_protocols

#: A :class:`ScoredRow`'s fields, in its order: one column each.
_SCORED = ("condition", "direction", "answered", "l2", "gt_in_frame", "l2_strict", "run", "error_x", "error_y", "parse_error", "asks_point")
#: How a row's official reading scores it: no reading, as the row itself, or otherwise (kept aside).
_NO_READING, _AS_SCORED, _OTHERWISE = 0, 1, 2
_INFRA = RowStatus.INFRA_ERROR.value
#: Distinct plugin-score tuples a table shares between its rows (past it, each row keeps its own).
_MAX_SHARED_SCORES = 1024
#: Distinct rows with no point score a table's read-back rows share (past it, each is its own).
_MAX_SHARED_ROWS = 1024
#: Values (of whole rows, twenty a row) that wait to be added to the columns together.
_PENDING_VALUES = 256 * 20


class SummaryTable:
    """A run's rows as its summary reads them (see the module's docstring).

    ``declared``: the scorers' metrics whose values are kept; ``protocols``: which scorer
    follows which protocol (``{scorer: protocol}``; default: as the registered scorers
    declare); ``keys``: the run's selection (a row of another key is left out). Add rows with
    :meth:`add`, then :meth:`close` once before reading.
    """

    def __init__(self, declared: Declared | None = None, protocols: Mapping[str, str] | None = None, keys: Container[str] | None = None) -> None:
        self.declared = declared or {}
        self._protocols = registered_protocols() if protocols is None else protocols
        #: the scorers following each protocol a row is read by (``following``'s candidates, found once)
        self._error_scorers = [n for n, p in self._protocols.items() if p == "normalized_l2"]
        self._hit_scorers = [n for n, p in self._protocols.items() if p == "marked_hit"]
        self._keys = keys
        #: each row's key's digest (the rows' order once closed)
        self._digests = bytearray()
        self._columns = {
            name: Column()
            for name in (
                *_SCORED,
                "status",
                "official_parser",
                "reading",
                "success",
                "success_answered",
                "prompt_tokens",
                "completion_tokens",
                "cost_usd",
                "retries",
            )
        }
        self.metrics = MetricColumns(self.declared)
        #: values only some rows have, by position
        self._aside: dict[str, dict[int, Any]] = {"officially_scored": {}, "plugin_scores": {}, "diagnosed": {}, "nan_key": {}}
        self._closed = False
        self._scored: list[ScoredRow] | None = None
        self._shared_scores: dict[Any, Any] = {}
        #: rows added, and the values of those not yet in the columns (row after row, each
        #: row's in the columns' order: see :meth:`_flush`; one flat list, so no object a row
        #: stays behind, nor in the interpreter's free list of tuples)
        self._added = 0
        self._pending: list[Any] = []
        #: where a row's diagnoses are (``{diagnosis: scorer}``), asked of the registry once a table
        self._diagnosing = diagnosing_scorers()

    def add(self, row: ResultRow) -> None:
        """Keep what the summary reads of ``row`` (left out when its key is not the run's)."""
        if self._closed:
            raise RuntimeError("SummaryTable.add after close()")
        if self._keys is not None and row.key not in self._keys:
            return
        self._digests += hashlib.blake2b(row.key.encode(), digest_size=16).digest()
        at = self._added
        self._added += 1
        protocols = self._protocols
        # (a run with no scorer of a protocol has none to find: a choice run's every row)
        error_scorer = _following(self._error_scorers, row.scores) if self._error_scorers else None
        hit_scorer = _following(self._hit_scorers, row.scores) if self._hit_scorers else None
        reading = row.official_reading
        official = official_view(row)  # officially_read's fields, without a copy of the row
        scored = scored_values(row, error_scorer)
        status = row.status if type(row.status) is RowStatus else RowStatus(row.status)
        state = _NO_READING
        if reading is not None or status is RowStatus.INFRA_ERROR:
            officially = scored_values(official, error_scorer)
            state = _AS_SCORED if officially == scored else _OTHERWISE  # ScoredRow's own equality: its fields'
            if state == _OTHERWISE:
                self._aside["officially_scored"][at] = ScoredRow(*officially)
        success = row.scores.get(hit_scorer) if hit_scorer is not None else None
        # the row's value of each column, in the columns' order ("success_answered" is None
        # where no marked_hit scorer gave a verdict), added with the next rows' (see _flush);
        # a list, not a tuple: CPython 3.11 keeps up to 2,000 freed tuples of twenty items
        # aside and never hands one out again (400 KB held)
        self._pending.extend([
            *scored,
            STATUS_TEXT[status],
            None if reading is None else reading.parser,
            state,
            None if success is None else (success or {}).get("success"),
            None if success is None else (success or {}).get("answered") is True,
            *_spent_values(row),
        ])
        if len(self._pending) >= _PENDING_VALUES:
            self._flush()
        if extra := plugin_scores(row.scores, protocols):
            # rows repeat a few verdicts (a choice scorer's true/false fields): one tuple each.
            # Only all-true/false ones: True == 1, and a summary tells a flag from a number
            shared = None
            if all(type(v) is bool for _, fields in extra for _, v in fields):
                shared = self._shared_scores.get(extra)
                if shared is None and len(self._shared_scores) < _MAX_SHARED_SCORES:
                    shared = self._shared_scores.setdefault(extra, extra)
            self._aside["plugin_scores"][at] = extra if shared is None else shared
        if (diagnosed := diagnosed_row(row, error_scorer, self._diagnosing)) is not None:
            self._aside["diagnosed"][at] = diagnosed
        if holds_nan(official.parse):  # nan_rows([official]), without its list
            self._aside["nan_key"][at] = row.key
        if self.metrics.declared:
            self.metrics.append(row_metric_flat(row, self.declared), row.condition, row.direction, row_category(row), row_metric_groups(row, self.declared))

    @property
    def _fields(self) -> dict[str, Column]:
        """The columns, with every row added so far (the pending ones flushed first)."""
        if self._pending:
            self._flush()
        return self._columns

    def _flush(self) -> None:
        """The pending rows' values into the columns, a column at a time: one call a column for
        a batch of rows, not twenty calls a row."""
        pending, self._pending = self._pending, []
        width = len(self._columns)
        for at, column in enumerate(self._columns.values()):
            column.extend(pending[at::width])

    def close(self) -> SummaryTable:
        """Keep each key's last row, keys in their digests' order (once; rows in that order after)."""
        if self._closed:
            return self
        self._closed = True
        self._flush()
        n = len(self._fields["run"])
        if n == 0:
            return self
        take = self._by_digest(n)
        self._digests = bytearray()
        if len(take) == n and bool((take == np.arange(n)).all()):
            return self  # rows one per key, already in order
        new_position = np.full(n, -1, dtype=np.int64)
        new_position[take] = np.arange(len(take))
        self._columns = {name: column.taken(take, new_position) for name, column in self._fields.items()}
        self._aside = {
            name: {int(new_position[old]): v for old, v in values.items() if new_position[old] >= 0} for name, values in self._aside.items()
        }
        if self.metrics.declared:
            self.metrics = self.metrics.taken(take)
        return self

    def _by_digest(self, n: int) -> np.ndarray:
        """The rows to keep, in order: each key's last row, keys by ascending digest."""
        digests = np.frombuffer(bytes(self._digests), dtype=">u8").reshape(n, 2)
        order = np.lexsort((digests[:, 1], digests[:, 0]))  # stable: a key's rows stay in file order
        ordered = digests[order]
        last_of_key = np.ones(n, dtype=bool)
        last_of_key[:-1] = (ordered[1:] != ordered[:-1]).any(axis=1)
        return order[last_of_key]

    def __len__(self) -> int:
        return len(self._fields["run"])

    # -- read back (after close) ------------------------------------------------------------
    @property
    def scored(self) -> Sequence[ScoredRow]:
        """Each row as its ``normalized_l2`` score gives it (see :func:`~povagent.run.summary_fields.scored_row`)."""
        self._check_closed()
        if self._scored is None:
            self._scored = _ScoredRows(self).built()  # built once, read by position at C speed
        return self._scored

    def officially_scored(self) -> Sequence[ScoredRow]:
        """The rows that have an official reading (and failed requests), as the reading scores them."""
        reading = self._fields["reading"].values()  # (read in one pass, not a position at a time)
        return Picked(_OfficialRows(self), array("q", (i for i, state in enumerate(reading) if state != _NO_READING)))

    def read_as_scored(self) -> bool:
        """Whether every row has an official reading that scores it as the row itself is scored
        (the official breakdown is then the main one)."""
        return all(state == _AS_SCORED for state in self._fields["reading"].values())

    def official_parser(self) -> str | None:
        """The parser whose official reading the first row with one records."""
        return next((p for p in self._fields["official_parser"].values() if p is not None), None)

    def unread(self) -> int:
        """Rows with an answer but no official reading (format 0 rows of the first days: :mod:`povagent.results.upgrade`)."""
        parsers, status = self._fields["official_parser"].values(), self._fields["status"].values()
        return sum(1 for parser, s in zip(parsers, status, strict=True) if parser is None and s != _INFRA)

    def has_success(self) -> bool:
        """Whether a ``marked_hit`` scorer scored any row."""
        return any(answered is not None for answered in self._fields["success_answered"].values())

    def success_rows(self) -> Iterator[dict[str, Any]]:
        """Each row's ``marked_hit`` verdict (a row it never scored: an unanswered failure)."""
        condition, direction = self._fields["condition"], self._fields["direction"]
        success, answered = self._fields["success"], self._fields["success_answered"]
        for i in range(len(self)):
            yield {"condition": condition[i], "direction": direction[i], "success": success[i], "answered": bool(answered[i])}

    def plugin_scores(self) -> Iterator[tuple[tuple[str, tuple[tuple[str, float], ...]], ...]]:
        """The fields of the scorers that follow no protocol, row by row (rows that have any)."""
        return iter(self._aside["plugin_scores"][i] for i in sorted(self._aside["plugin_scores"]))

    def diagnosed(self) -> Iterator[DiagnosedRow]:
        """The diagnosed rows' diagnoses, in order."""
        return iter(self._aside["diagnosed"][i] for i in sorted(self._aside["diagnosed"]))

    def nan_keys(self) -> list[str]:
        """Keys of the rows whose official reading holds a NaN coordinate, sorted."""
        return sorted(self._aside["nan_key"].values())

    def by_run(self) -> dict[int, Sequence[ScoredRow]]:
        """Each run's rows (runs in order)."""
        positions: dict[int, array] = defaultdict(lambda: array("q"))
        for i, run in enumerate(self._fields["run"].values()):
            positions[run].append(i)
        return {run: Picked(self.scored, at) for run, at in sorted(positions.items())}

    def statuses(self) -> Counter[str]:
        """How many rows have each status."""
        return Counter(self._fields["status"].values())

    def usage(self) -> UsageTotals:
        """The rows' tokens, cost and retries, summed in row order (unstated tokens: 0)."""
        prompt, completion, cost, retries = (self._fields[name].values() for name in _SPENT)
        return UsageTotals.summed(prompt, completion, cost, retries, unstated_tokens=0)

    def field(self, name: str) -> Column:
        """One kept field's column."""
        return self._fields[name]

    def aside(self, name: str) -> Mapping[int, Any]:
        """Values only some rows have, by position."""
        return self._aside.get(name, {})

    def nbytes(self) -> int:
        """Bytes the columns hold (texts and values kept aside not counted)."""
        return sum(c.nbytes() for c in self._fields.values()) + len(self._digests) + self.metrics.nbytes()

    def _check_closed(self) -> None:
        if not self._closed:
            raise RuntimeError("SummaryTable read before close()")


#: A row's spending, read in one call.
_SPENT = ("prompt_tokens", "completion_tokens", "cost_usd", "retries")
_spent_values = attrgetter(*_SPENT)


def _following(names: list[str], scores: Mapping[str, Any]) -> str | None:
    """:func:`~povagent.scoring.score_protocols.following` of a protocol whose scorers are ``names``."""
    return next((n for n in names if scores and n in scores), names[0] if names else None)


class _ScoredRows(Sequence[ScoredRow]):
    """A table's rows as :class:`ScoredRow` objects, built together when one is first read and
    kept while this view lives (a summary reads each row a dozen times, by slice; the table
    itself stays in columns)."""

    __slots__ = ("_columns", "_n", "_rows")

    def __init__(self, table: SummaryTable) -> None:
        self._columns = [table.field(name) for name in _SCORED]
        self._n = len(table)
        self._rows: list[ScoredRow] | None = None

    def built(self) -> list[ScoredRow]:
        """Every row, in order (built at the first read, then kept). Rows with no point score
        (a choice run's every row, a point run's failures) repeat a few field values: such rows
        share one (frozen) object a set of values, which cost a summary ~2 us a row to make."""
        if self._rows is None:
            shared: dict[tuple[Any, ...], ScoredRow] = {}
            rows = []
            for values in zip(*(column.values() for column in self._columns), strict=True):
                # no number but the run (an int, never a flag: True == 1 would pass for it), so
                # equal values are values of the same types
                if values[3] is None and values[4] is None and values[5] is None and values[7] is None and values[8] is None and type(values[6]) is int:
                    row = shared.get(values)
                    if row is None:
                        row = ScoredRow(*values)
                        if len(shared) < _MAX_SHARED_ROWS:
                            shared[values] = row
                else:
                    row = ScoredRow(*values)
                rows.append(row)
            self._rows = rows
        return self._rows

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, i: int) -> ScoredRow: ...

    @overload
    def __getitem__(self, i: slice) -> Sequence[ScoredRow]: ...

    def __getitem__(self, i: int | slice) -> ScoredRow | Sequence[ScoredRow]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self._n))]
        return self.built()[i]


class _OfficialRows(_ScoredRows):
    """A table's rows as their official readings score them (the row itself where the same)."""

    __slots__ = ("_otherwise",)

    def __init__(self, table: SummaryTable) -> None:
        super().__init__(table)
        self._otherwise = table.aside("officially_scored")

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, int) and i in self._otherwise:
            return self._otherwise[i]
        return super().__getitem__(i)

"""Slices hold positions: a breakdown of rows built on demand is the breakdown of the rows in hand."""

from __future__ import annotations

from array import array
from collections.abc import Sequence

from povagent.scoring.breakdown import Picked, ScoredRow, breakdown


class Built(Sequence[ScoredRow]):
    """Rows made when read (as a run summary's columns make them), counting how many are alive."""

    def __init__(self, rows: list[ScoredRow]) -> None:
        self._rows = rows
        self.reads = 0

    def __len__(self) -> int:
        return len(self._rows)

    def __getitem__(self, i):  # type: ignore[override]
        self.reads += 1
        r = self._rows[i]
        return ScoredRow(r.condition, r.direction, r.answered, r.l2, r.gt_in_frame, r.l2_strict, r.run, r.error_x, r.error_y, r.parse_error)


def rows() -> list[ScoredRow]:
    return [
        ScoredRow(c, d, answered=(n % 5 != 0), l2=n / 40, gt_in_frame=n % 3 == 0, l2_strict=n / 30, run=run, error_x=-n / 50, error_y=n / 70)
        for run in range(2) for n, (c, d) in enumerate((c, d) for c in ("a", "b", "c") for d in ("left", "right", "up", "down"))
    ]  # fmt: skip


def test_a_breakdown_of_rows_built_when_read_is_the_breakdown_of_the_rows():
    built = Built(rows())
    assert breakdown(built) == breakdown(rows())
    assert built.reads > 0


def test_a_slice_of_a_slice_reads_the_rows_underneath():
    base = list(range(10))
    evens = Picked(base, array("q", [0, 2, 4, 6, 8]))
    picked = Picked(evens, array("q", [1, 3]))
    assert list(picked) == [2, 6] and picked[1] == 6 and len(picked) == 2
    assert list(picked[::-1]) == [6, 2]

"""What a summary keeps of a run's rows: a few bytes a key in columns, read back as the rows were."""

from __future__ import annotations

import hashlib
import json
import math
import tracemalloc
from typing import Any

import numpy as np
import pytest

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import ResultRow, RowStatus, iter_rows
from povagent.run.row_columns import Column
from povagent.run.runner import run_pipeline
from povagent.run.summary import summarize_rows, summarize_run
from povagent.run.summary_fields import scored_row
from povagent.run.summary_table import SummaryTable
from povagent.scoring.breakdown import breakdown
from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric, valued_row

#: The most the table may hold a key (bytes, traced): its official score, usage and metric values.
BYTES_PER_KEY = 256

DECLARED = {
    "official": (
        Metric("mean_l2", "lower", "mean", "l2", "Mean L2", "mean error"),
        Metric("frame_accuracy", "higher", "rate", "gt_in_frame", "GT in frame", "share in frame"),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "answered / all", over="all"),
    )
}


def row(n: int, run: int = 0, l2: float | None = 0.25, status: RowStatus = RowStatus.ANSWERED, condition: str = "a", **extra: Any) -> ResultRow:
    scores = {} if l2 is None else {"official": {"answered": True, "l2": l2, "l2_strict": l2, "gt_in_frame": l2 < 0.5, "error_x": -l2, "error_y": l2 / 2}}
    return ResultRow(key=f"h/{n}/left/{condition}#{run}", instance_id=f"h/{n}/left/{condition}", house_id="h", pair_id=str(n),
                     direction="left" if n % 2 else "right", condition=condition, run=run, status=status, scores=scores,
                     prompt_tokens=100 + n, completion_tokens=n, cost_usd=0.001 * n, **extra)  # fmt: skip


def in_table_order(rows: list[ResultRow]) -> list[ResultRow]:
    """``rows`` in the order a table reads them back: their keys' BLAKE2b-128 digests, ascending."""
    return sorted(rows, key=lambda r: hashlib.blake2b(r.key.encode(), digest_size=16).digest())


def test_a_column_gives_back_each_value_as_it_was_appended():
    labels = [f"label {i}" for i in range(300)]  # past the 128 a byte holds
    values = [0.5, -0.0, math.inf, 3, 119, 120, -1, -(2**53), 2**60, True, False, None, "a", "a", "b", ("kept", "aside"), 1e-300, *labels]
    column = Column()
    for v in values:
        column.append(v)
    back = [column[i] for i in range(len(values))]
    assert back == values and [type(v) for v in back] == [type(v) for v in values]
    assert math.copysign(1.0, back[1]) == -1.0  # the sign of a zero is kept
    assert back[12] is back[13]  # one string a label, however many rows carry it
    nan = Column()
    nan.append(float("nan"))
    assert math.isnan(nan[0])


def test_a_column_extended_by_a_batch_holds_what_appending_each_value_holds():
    values = [None, 0.5, "a", 3, -0.0, 2**60, ("kept", "aside"), *(f"label {i}" for i in range(200)), True, 1e-300, "a"]
    one_by_one, batched = Column(), Column()
    for v in values:
        one_by_one.append(v)
    batched.extend(values[:7])
    batched.extend(values[7:])
    assert batched.values() == one_by_one.values() == values and batched.nbytes() == one_by_one.nbytes()
    assert [type(v) for v in batched.values()] == [type(v) for v in values]


def test_a_batch_repeating_one_object_holds_what_appending_it_each_time_holds():
    aside, nan = ("kept", "aside"), float("nan")
    for value in (None, True, 0.25, -0.0, nan, 3, 2**60, "new label", aside):
        one_by_one, batched = Column(), Column()
        for v in (0.5, value, value, value):
            one_by_one.append(v)
        batched.extend([0.5])
        batched.extend([value, value, value])
        back = batched.values()
        assert [type(v) for v in back] == [type(v) for v in one_by_one.values()] and batched.nbytes() == one_by_one.nbytes()
        assert [repr(v) for v in back] == [repr(v) for v in one_by_one.values()]  # -0.0 and NaN too
        if isinstance(value, (str, tuple)):
            assert batched[3] is batched[1]  # one object, as appended


def test_a_batch_of_equal_but_different_objects_keeps_each_ones_type():
    column = Column()
    column.extend([1, 1.0, True, 1])  # equal, not one object: placed one by one
    assert [type(v) for v in column.values()] == [int, float, bool, int]


def test_taking_rows_of_a_column_keeps_their_values_and_what_was_kept_aside():
    column = Column()
    for v in [1.5, ("aside",), None, "x", 7]:
        column.append(v)
    positions = np.array([4, 1, 3])
    new_position = np.full(5, -1)
    new_position[positions] = np.arange(3)
    taken = column.taken(positions, new_position)
    assert [taken[i] for i in range(3)] == [7, ("aside",), "x"]


def test_a_key_costs_the_table_a_few_hundred_bytes_however_long_its_row(write_pipeline):
    result = run_pipeline(load_pipeline(write_pipeline()))
    done = list(iter_rows(result.run_dir / "results.jsonl"))
    long = done[0].model_copy(update={"key": "long", "sentence": "s" * 5000, "exchanges": done[0].exchanges * 20})
    rows = [r.model_copy(update={"key": f"{r.key}/{i}"}) for i in range(200) for r in [*done, long]]
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        table = SummaryTable(DECLARED)
        for r in rows:
            table.add(r)
        table.close()
        held = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert len(table) == len(rows)
    assert held / len(rows) < BYTES_PER_KEY, f"{held / len(rows):.0f} bytes a key"


def test_the_last_row_of_a_key_counts():
    first, other, again = row(1, l2=0.9), row(2, l2=0.1), row(1, l2=0.3)
    assert summarize_rows([first, other, again]) == summarize_rows([again, other]) == summarize_rows([other, again])
    assert summarize_rows([first, other, again])["overall"]["mean_l2"] == pytest.approx(0.2)


def test_a_table_summarizes_what_the_rows_as_objects_give():
    rows = [
        *(row(n, run, l2=(n * 7 % 10) / 10 + 0.05 * run) for n in range(12) for run in range(3)),
        row(20, status=RowStatus.PARSE_ERROR, l2=None),
        row(21, status=RowStatus.INFRA_ERROR, l2=None),
        row(22, condition="b"),
        row(1, l2=0.45),  # key h/1/left/a#0 again: its last row counts
    ]
    summary = summarize_rows(rows, None, DECLARED)
    last = in_table_order(list({r.key: r for r in rows}.values()))  # the rows one per key
    expected = breakdown([scored_row(r, "official") for r in last])
    for section in ("overall", "per_condition", "per_direction", "per_condition_direction", "pooled", "per_run"):
        assert summary[section] == expected[section], section
    assert summary["metrics"] == metrics_breakdown([valued_row(r, DECLARED) for r in last], DECLARED)
    assert summary["rows"]["done"] == len(last) and summary["rows"]["parse_error"] == 1 and summary["rows"]["infra_error"] == 1
    assert summary["usage"]["prompt_tokens"] == sum(r.prompt_tokens or 0 for r in last)
    assert summary["usage"]["cost_usd"] == sum(r.cost_usd or 0.0 for r in last)


def test_the_summary_a_run_writes_is_the_summary_of_its_results_file(write_pipeline):
    result = run_pipeline(load_pipeline(write_pipeline(runs=2)))
    written = json.loads((result.run_dir / "summary.json").read_text())
    again = json.loads(json.dumps(summarize_run(result.run_dir / "results.jsonl"), default=str))
    for section in ("overall", "per_condition", "per_direction", "per_run", "rows", "usage", "official_parse"):
        assert written.get(section) == again.get(section), section


def test_rows_of_keys_outside_the_selection_are_left_out_and_missing_keys_counted():
    rows = [row(1), row(2), row(3)]
    summary = summarize_rows(rows, {rows[0].key, rows[2].key, "h/9/left/a#0"})
    assert summary["rows"]["done"] == 2 and summary["rows"]["missing"] == 1 and summary["rows"]["total"] == 3


def test_each_row_reads_back_as_its_scored_row_and_as_its_official_reading_scores_it():
    from povagent.answers.spec import ParsedAnswer
    from povagent.results.official_reading import officially_read
    from povagent.results.rows import OfficialReading

    unread = OfficialReading(parser="official", parse=ParsedAnswer(status="unparseable", reason="no JSON"))
    agreeing = OfficialReading(parser="official", parse=ParsedAnswer(status="ok", x=1.0, y=2.0), scores=row(1).scores)
    otherwise = OfficialReading(parser="official", parse=ParsedAnswer(status="ok", x=1.0, y=2.0), scores=row(2, l2=0.75).scores)
    rows = [row(0), row(1, official_reading=agreeing), row(2, official_reading=otherwise), row(3, official_reading=unread),
            row(4, status=RowStatus.INFRA_ERROR, l2=None), row(5, category="Relative Direction", official_reading=unread)]  # fmt: skip
    table = SummaryTable(DECLARED)
    for r in rows:
        table.add(r)
    table.close()
    rows = in_table_order(rows)
    assert list(table.scored) == [scored_row(r, "official") for r in rows]
    officially = [scored_row(officially_read(r), "official") for r in rows if r.official_reading is not None or r.status is RowStatus.INFRA_ERROR]
    assert list(table.officially_scored()) == officially and not table.read_as_scored()
    # the reading that scores otherwise is its own
    scoring_otherwise = next(r for r in rows if r.official_reading is otherwise)
    read = [r for r in rows if r.official_reading is not None or r.status is RowStatus.INFRA_ERROR]
    assert list(table.officially_scored())[read.index(scoring_otherwise)] != list(table.scored)[rows.index(scoring_otherwise)]


def test_rows_with_no_point_score_read_back_as_shared_objects_of_the_same_values_and_types():
    from povagent.results.rows import ResultRow as Row

    failures = [row(n, status=RowStatus.PARSE_ERROR, l2=None) for n in range(4)]
    flagged = Row.model_construct(**{**dict(failures[0]), "key": "flag", "run": True})  # True == 1, but a flag
    counted = Row.model_construct(**{**dict(failures[0]), "key": "count", "run": 1})
    table = SummaryTable(DECLARED)
    for r in [*failures, flagged, counted, row(9)]:
        table.add(r)
    read = list(table.close().scored)
    ordered = in_table_order([*failures, flagged, counted, row(9)])
    assert read == [scored_row(r, "official") for r in ordered]
    at = {r.key: i for i, r in enumerate(ordered)}
    left, right = ([read[at[r.key]] for r in failures if r.direction == side] for side in ("left", "right"))
    assert left[0] is left[1] and right[0] is right[1] and left[0] is not right[0]  # the same values: one object (frozen)
    as_flag, as_count = read[at["flag"]], read[at["count"]]
    assert type(as_flag.run) is bool and type(as_count.run) is int and as_flag is not as_count

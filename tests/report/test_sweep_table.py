"""The sweep command's tables as rows: the dry run's and the finished cells'."""

from __future__ import annotations

from typing import Any

from povagent.report.sweep_table import dry_run_table, official_cells, sweep_table
from povagent.run.summary_model import RunSummary
from povagent.run.sweep_estimate import DryRunCell, TurnCount

CELL = {"n": 3, "n_total": 4, "mean_l2": 0.25, "response_rate": 0.75}


def cell(**given: Any) -> dict[str, Any]:
    """A whole breakdown cell: ``given`` and the rest empty."""
    empty = {"n": 0, "n_total": 0, "response_rate": None, "mean_l2": None, "std_l2": None, "pct_in_frame": None,
             "mean_l2_strict": None, "mean_abs_x": None, "mean_abs_y": None, "n_parse_error": 0}  # fmt: skip
    return {**empty, **given}


def breakdown(overall: dict[str, Any]) -> dict[str, Any]:
    return {"overall": cell(**overall), "per_condition": {}, "per_direction": {}, "per_condition_direction": {},
            "aggregation": "mean of per-run means", "runs": [0], "n_parse_error": 0}  # fmt: skip


def summary(overall: dict[str, Any] | None = None, rows: dict[str, Any] | None = None, **sections: Any) -> RunSummary:
    """A run's summary: its overall cell, its row counts and any other section (a cell of the
    ``official_parse`` section given as its overall cell; the pipeline as the names to differ)."""
    data: dict[str, Any] = breakdown(overall or {})
    if rows is not None:
        data["rows"] = {"total": 0, "done": 0, "missing": 0, "answered": 0, "parse_error": 0, "infra_error": 0, **rows}
    if "official_parse" in sections:
        data["official_parse"] = {**breakdown(sections.pop("official_parse")["overall"]), "parser": "official", "rows_without_reading": 0}
    if "pipeline" in sections:
        names = {
            "backend": "center",
            "model": "center",
            "profile": None,
            "strategy": "basic",
            "parser": "official",
            "scorers": ["official"],
            "config_hash": "h",
        }
        data["pipeline"] = {**names, **sections.pop("pipeline")}
    return RunSummary.model_validate({**data, **sections})


def test_a_multi_turn_cell_lists_each_turn_under_it_and_the_total_sums_the_cells():
    two_turns = DryRunCell("a", 4, 1, 6, 600, 512, [TurnCount(1, 3, 400, 256), TurnCount(2, 3, 200, 256, note="taken only sometimes")])
    one_turn = DryRunCell("b", 4, 0, 4, 100, 256)
    columns, rows, notes = dry_run_table([two_turns, one_turn])
    assert [r[0] for r in rows] == ["a", "  turn 1", "  turn 2*", "b", "[bold]total"]
    assert rows[-1][1:] == ["[bold]8", "[bold]1", "[bold]10", "[bold]700", "[bold]768"]
    assert notes == ["turn 2: taken only sometimes (counted for every key)"]
    assert len(columns) == len(rows[0])


def test_official_parse_columns_appear_once_a_cells_repair_changed_a_number():
    lenient = summary(CELL, {"total": 4}, official_parse={"overall": {"mean_l2": 0.5, "response_rate": 0.5}})
    official = summary(CELL, {"total": 4}, pipeline={"parser": "official"})
    columns, rows = sweep_table({"lenient": lenient, "official": official}, {"lenient": None, "official": None}, lambda s: s.official_parse is not None)
    assert [c[0] for c in columns] == ["cell", "mean L2", "resp. rate", "answered / total", "official parse L2", "official parse resp."]
    assert rows == [["lenient", "0.250", "75.0%", "3 / 4", "0.500", "50.0%"], ["official", "0.250", "75.0%", "3 / 4", "=", "="]]


def test_a_lenient_cell_without_an_official_reading_is_marked_unknown():
    assert official_cells(summary(pipeline={"parser": "json"}), lambda s: True) == ("?", "?")


def test_a_repair_that_changed_no_number_is_marked_as_reading_officially():
    repaired = summary(official_parse={"overall": {"mean_l2": 0.5, "response_rate": 0.5}})
    assert official_cells(repaired, lambda s: False) == ("=", "=")

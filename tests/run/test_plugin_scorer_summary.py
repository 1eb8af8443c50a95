"""summary.json's ``scorers`` section: a plugin scorer's own fields, counted or averaged over the
rows it scored, so its author finds the metric without reading every row."""

from __future__ import annotations

from typing import Any

from povagent.results.rows import ResultRow, RowStatus
from povagent.run.summary import summarize_rows


def row(n: int, scores: dict[str, dict[str, Any]], status: RowStatus = RowStatus.ANSWERED) -> ResultRow:
    return ResultRow(key=f"h/{n}/left/a#0", instance_id=f"h/{n}/left/a", house_id="h", pair_id=str(n), direction="left",
                     condition="a", status=status, scores=scores)  # fmt: skip


def summary(*rows: ResultRow) -> dict[str, Any]:
    return summarize_rows(rows)


def test_true_false_fields_are_counted_and_number_fields_averaged():
    out = summary(
        row(1, {"hit": {"success": True, "l2": 0.1, "label": "near"}}),
        row(2, {"hit": {"success": False, "l2": 0.5, "label": "far"}}),
        row(3, {"hit": {"success": True, "l2": 0.3, "label": "near"}}),
    )
    assert out["scorers"] == {"hit": {"success": {"n": 3, "true": 2, "rate": 2 / 3}, "l2": {"n": 3, "mean": 0.3}}}


def test_rows_the_scorer_did_not_score_are_left_out_of_its_counts():
    out = summary(row(1, {"hit": {"success": True}}), row(2, {}, RowStatus.PARSE_ERROR), row(3, {}, RowStatus.INFRA_ERROR))
    assert out["scorers"]["hit"]["success"] == {"n": 1, "true": 1, "rate": 1.0}


def test_a_field_mixing_true_false_and_numbers_is_left_out_rather_than_averaged():
    out = summary(row(1, {"hit": {"odd": True, "l2": 0.2}}), row(2, {"hit": {"odd": 0.5, "l2": 0.4}}))
    assert set(out["scorers"]["hit"]) == {"l2"}


def test_official_and_success_keep_their_own_sections_and_add_no_scorers_section():
    official = {"answered": True, "l2": 0.2, "l2_strict": 0.2, "gt_in_frame": True}
    out = summary(row(1, {"official": official}), row(2, {"official": official}))
    assert "scorers" not in out and out["overall"]["mean_l2"] == 0.2

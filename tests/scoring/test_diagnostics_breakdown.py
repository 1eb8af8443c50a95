"""summary.json's ``diagnostics`` section from row fields: shares, the bias index, relation rates."""

from __future__ import annotations

import pytest

from povagent.scoring.diagnostics_breakdown import DiagnosedRow, diagnostics_breakdown


def row(iid: str, cond: str = "a", direction: str = "left", step: str | None = "correct", vote: bool | None = None,
        relation: bool | None = True, l2: float | None = 0.1) -> DiagnosedRow:
    return DiagnosedRow(iid, cond, direction, l2, step, vote, relation)


def test_failure_steps_are_shares_of_diagnosed_rows():
    out = diagnostics_breakdown([row("1", step="frame"), row("2", step="viewpoint"), row("3"), row("4")])
    steps = out["per_condition"]["a"]["failure_steps"]
    assert steps == {"frame": 0.25, "anchor": 0.0, "viewpoint": 0.25, "placement": 0.0, "correct": 0.5}


def test_the_bias_index_counts_only_rows_that_voted_and_averages_each_instance_over_runs():
    # instance 1 voted twice (egocentric once), instance 2 once (egocentric): (0.5 + 1) / 2
    rows = [row("1", vote=True), row("1", vote=False), row("2", vote=True), row("3", vote=None)]
    cell = diagnostics_breakdown(rows)["per_condition"]["a"]
    assert cell["egocentric_bias"] == pytest.approx(0.75) and cell["bias_n"] == 3
    lo, hi = cell["egocentric_bias_ci"]
    assert 0.5 <= lo <= 0.75 <= hi <= 1.0


def test_given_has_no_bias_index_even_with_votes():
    cell = diagnostics_breakdown([row("1", cond="c", vote=True)])["per_condition"]["c"]
    assert cell["egocentric_bias"] is None and cell["egocentric_bias_ci"] is None and cell["bias_n"] == 0


def test_relation_success_per_direction_sits_beside_the_official_mean():
    rows = [row("1", relation=True, l2=0.1), row("2", relation=False, l2=0.3), row("3", direction="up", relation=True, l2=0.2)]
    cell = diagnostics_breakdown(rows)["per_condition"]["a"]
    assert cell["relation_success"] == pytest.approx(2 / 3) and cell["relation_n"] == 3
    assert cell["per_direction"]["left"] == {"n": 2, "relation_success": 0.5, "official_mean_l2": pytest.approx(0.2)}
    assert cell["per_direction"]["up"]["relation_success"] == 1.0


def test_relation_alone_gives_rates_without_steps():
    cell = diagnostics_breakdown([row("1", step=None, relation=False)])["per_condition"]["a"]
    assert cell["n_diagnosed"] == 0 and cell["failure_steps"]["correct"] is None and cell["relation_success"] == 0.0


def test_no_diagnosed_row_gives_no_section():
    assert diagnostics_breakdown([row("1", step=None, relation=None)]) is None
    assert diagnostics_breakdown([]) is None

"""A metric whose overall is the mean of its category means (``category_mean``: VSI-Bench's
overall, each question type counted once), with listed categories first averaged into one; the
per-category cells are the plain means."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric, valued_row

SCORE = Metric(
    "score", "higher", "mean", "score", "Score", "per question", over="all", unscored=0.0, category_mean=True, merged_categories=(("dir_easy", "dir_hard"),)
)
DECLARED = {"mine": (SCORE,)}


def row(category: str, score: float | None):
    """A row of ``category``; ``score=None``: a reply read as nothing, which no scorer scored."""
    scores = {} if score is None else {"mine": {"score": score, "answered": True, "category": category}}
    return SimpleNamespace(
        status="parse_error" if score is None else "answered",
        scores=scores,
        condition="",
        direction="",
        pair_id=f"{category}-{id(scores)}",
        run=0,
        category=category,
    )


def breakdown(rows, declared=DECLARED):
    return metrics_breakdown([valued_row(r, declared) for r in rows], declared, n_boot=50)["mine"]


#: VLMEvalKit's VsiBench._aggregate: the group merges only when each of its categories has rows.
WHOLE = {
    "mine": (
        Metric(
            "score",
            "higher",
            "mean",
            "score",
            "Score",
            "per question",
            over="all",
            unscored=0.0,
            category_mean=True,
            merged_categories=(("dir_easy", "dir_mid", "dir_hard"),),
            merge_only_whole=True,
        ),
    )
}


def test_the_overall_is_the_mean_of_the_category_means_not_of_the_rows():
    # counting: 1, 1, 1, 0 -> 0.75; size: 0 -> 0; overall (0.75 + 0) / 2, not 3/5
    cells = breakdown([row("counting", 1.0), row("counting", 1.0), row("counting", 1.0), row("counting", 0.0), row("size", 0.0)])
    assert cells["overall"]["score"]["value"] == pytest.approx(0.375)
    assert cells["per_category"]["counting"]["score"]["value"] == pytest.approx(0.75)
    assert cells["overall"]["score"]["n"] == 5


def test_merged_categories_are_averaged_into_one_first():
    # dir_easy 1, dir_hard 0 (two rows) -> direction 0.5; size 1 -> overall 0.75 (not (1 + 0 + 1) / 3)
    cells = breakdown([row("dir_easy", 1.0), row("dir_hard", 0.0), row("dir_hard", 0.0), row("size", 1.0)])
    assert cells["overall"]["score"]["value"] == pytest.approx(0.75)


def test_a_group_with_a_category_missing_still_merges_by_default():
    # dir_easy 1, dir_hard 0 merge into 0.5 though dir_mid has no row; with size 1 -> 0.75
    cells = breakdown(
        [row("dir_easy", 1.0), row("dir_hard", 0.0), row("size", 1.0)], {"mine": (replace(SCORE, merged_categories=(("dir_easy", "dir_mid", "dir_hard"),)),)}
    )
    assert cells["overall"]["score"]["value"] == pytest.approx(0.75)


def test_a_group_merging_only_when_whole_keeps_its_categories_apart_when_one_has_no_row():
    # dir_easy 1, dir_hard 0, size 1: three types -> 2/3 (VLMEvalKit), not (0.5 + 1) / 2
    cells = breakdown([row("dir_easy", 1.0), row("dir_hard", 0.0), row("size", 1.0)], WHOLE)
    assert cells["overall"]["score"]["value"] == pytest.approx(2 / 3)


def test_a_group_merging_only_when_whole_merges_when_every_category_has_rows():
    # dir_easy 1, dir_mid 1, dir_hard 0 -> 2/3; size 0 -> overall 1/3
    cells = breakdown([row("dir_easy", 1.0), row("dir_mid", 1.0), row("dir_hard", 0.0), row("dir_hard", 0.0), row("size", 0.0)], WHOLE)
    assert cells["overall"]["score"]["value"] == pytest.approx(1 / 3)


def test_an_unread_reply_counts_zero_in_its_category():
    cells = breakdown([row("counting", 1.0), row("counting", None), row("size", 1.0)])
    assert cells["per_category"]["counting"]["score"]["value"] == pytest.approx(0.5)
    assert cells["overall"]["score"]["value"] == pytest.approx(0.75)


def test_the_declaration_round_trips():
    assert Metric.declared("score", SCORE.describe()) == SCORE
    assert Metric.declared("score", WHOLE["mine"][0].describe()) == WHOLE["mine"][0]
    assert "merge_only_whole" not in SCORE.describe()  # said only when set

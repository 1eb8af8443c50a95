"""Scoring prediction files against a dataset: official rows or our own results rows.

``povagent score`` and the reports use this. Official rows (see POVBENCH.md) are scored as the
official scorer does: ``parse_error`` or a missing/unknown ``predicted_image`` (A/B) makes a row
unanswered; several ``predicted_points`` are scored by their centroid (the closest point's
error is kept beside it). Our results rows are re-scored from their stored prediction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from povagent.dataset.loader import Dataset
from povagent.dataset.models import Condition
from povagent.errors import PredictionsError
from povagent.scoring.official import (
    UNANSWERED,
    OfficialScore,
    closest_point_l2,
    score_point,
    scoring_frame,
)
from povagent.scoring.breakdown import ScoredRow, breakdown


@dataclass(frozen=True)
class ScoredPrediction:
    """One prediction with its official score (``instance_id`` is ``None`` if not in the dataset)."""

    instance_id: str | None
    condition: str
    direction: str
    run: int
    score: OfficialScore
    l2_closest: float | None = None


def _centroid(points: list[list[float]] | list[tuple[float, float]]) -> tuple[float, float]:
    xs = [float(p[0]) for p in points]
    ys = [float(p[1]) for p in points]
    return sum(xs) / len(xs), sum(ys) / len(ys)


def score_official_rows(rows: Iterable[Any], dataset: Dataset) -> tuple[list[ScoredPrediction], list[str]]:
    """Score official prediction rows; returns scored rows and warnings (unknown instances).

    ``rows`` are objects with the official fields as attributes (see
    :func:`povagent.results.official_format.read_official_predictions`).
    """
    scored: list[ScoredPrediction] = []
    warnings: list[str] = []
    for row in rows:
        cond = str(row.type).lower()
        direction = str(row.direction).lower()
        inst = dataset.instance_for(row.house_id, row.pair_id, direction, cond)
        if inst is None:
            warnings.append(f"no instance {row.house_id}/{row.pair_id}/{direction}/{cond} in the dataset")
            continue
        run = int(getattr(row, "run", 0) or 0)
        x, y = row.predicted_x, row.predicted_y
        points = getattr(row, "predicted_points", None) or None
        if points:
            x, y = _centroid(points)
        if row.parse_error or x is None or y is None:
            scored.append(ScoredPrediction(inst.id, cond, direction, run, UNANSWERED))
            continue
        frame = scoring_frame(inst, image_path=row.predicted_image) if inst.condition is not Condition.GIVEN else inst.frames[0]
        if inst.condition is not Condition.GIVEN and row.predicted_image is None:
            frame = None
        score = score_point(inst, frame, float(x), float(y))
        closest = None
        if points and len(points) > 1 and frame is not None:
            closest = closest_point_l2(inst, frame, [(float(p[0]), float(p[1])) for p in points])
        scored.append(ScoredPrediction(inst.id, cond, direction, run, score, closest))
    return scored, warnings


def score_result_rows(rows: Iterable[Any], dataset: Dataset) -> tuple[list[ScoredPrediction], list[str]]:
    """Re-score our own results rows from their stored predictions, each as the official runner
    reads its answer (a row parsed leniently by its recorded official reading)."""
    from povagent.results.official_reading import official_rows

    scored: list[ScoredPrediction] = []
    rows, warnings = official_rows(rows)
    for row in rows:
        inst = dataset.instance(row.instance_id)
        if inst is None:
            warnings.append(f"no instance {row.instance_id} in the dataset")
            continue
        p = row.prediction
        answered = row.status == "answered" and p.x is not None and p.y is not None
        if not answered:
            scored.append(ScoredPrediction(inst.id, row.condition, row.direction, row.run, UNANSWERED))
            continue
        frame = scoring_frame(inst, p.selected_image, p.image_path)
        score = score_point(inst, frame, float(p.x), float(p.y))
        scored.append(ScoredPrediction(inst.id, row.condition, row.direction, row.run, score))
    return scored, warnings


def summary_of(scored: Iterable[ScoredPrediction]) -> dict[str, Any]:
    """The official breakdown (overall, per condition, per direction, condition x direction)."""
    return breakdown(
        ScoredRow(s.condition, s.direction, s.score.answered, s.score.l2, s.score.gt_in_frame, s.score.l2_strict)
        for s in scored
    )


def load_predictions(path: str | Path) -> tuple[str, list[Any]]:
    """Read a predictions path: our ``results.jsonl`` (or a run folder) or official rows.

    Returns ``("results", rows)`` or ``("official", rows)``.
    """
    from povagent.results.rows import read_rows

    p = Path(path)
    if p.is_dir() and (p / "results.jsonl").exists():
        p = p / "results.jsonl"
    if p.is_file() and p.suffix == ".jsonl" and _holds_result_rows(p):
        rows = read_rows(p)
        if not rows:
            raise PredictionsError(f"{p}: no complete result rows")
        return "results", rows
    if not p.exists():
        raise PredictionsError(f"{p}: predictions file or folder not found")
    from povagent.results.official_format import read_official_predictions

    return "official", read_official_predictions(p)


def _holds_result_rows(path: Path) -> bool:
    """Whether a JSON-lines file holds our result rows (``key`` and ``status``), not official rows."""
    import json

    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if not line.strip():
                continue
            try:
                first = json.loads(line)
            except json.JSONDecodeError:
                return True  # let the results reader report what it can read
            return isinstance(first, dict) and "key" in first and "status" in first
    return True


def score_predictions(path: str | Path, dataset: Dataset) -> tuple[dict[str, Any], list[str]]:
    """Score a predictions path against ``dataset``: the summary and any warnings."""
    kind, rows = load_predictions(path)
    scorer = score_result_rows if kind == "results" else score_official_rows
    scored, warnings = scorer(rows, dataset)
    if not scored:
        raise PredictionsError(f"{path}: none of the predictions matches an instance of the dataset")
    return summary_of(scored), warnings


def format_number(v: float | None, digits: int = 3) -> str:
    """A mean for a table: ``-`` when missing."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{v:.{digits}f}"

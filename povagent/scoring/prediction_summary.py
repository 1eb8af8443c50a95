"""The breakdown of scored predictions (``povagent score``'s summary): overall, per condition,
per direction and condition x direction, with a run's ``metrics`` section when the scorer is given.

Scoring a prediction file's rows is :mod:`povagent.scoring.predictions`; this module only sums
what it scored, the way a run's summary sums its rows.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from povagent.scoring.breakdown import ScoredRow, breakdown
from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Declared, valued_row
from povagent.scoring.predictions import ScoredPrediction


@dataclass(frozen=True)
class _ScoredAsRow:
    """A scored prediction as :func:`~povagent.scoring.metrics.row_metric_values` reads a row:
    its status and, under each scorer named, the fields that scorer gives its point."""

    status: str
    scores: dict[str, dict[str, Any]]
    condition: str | None
    direction: str | None


def summary_of(scored: Iterable[ScoredPrediction], scorers: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The breakdown (overall, per condition, per direction, condition x direction); several
    runs are averaged per run, the paper's way, with the pooled numbers under ``pooled``.

    With ``scorers`` (``{name: scorer}``, the ``normalized_l2`` scorer: ``povagent score``'s)
    the summary has the ``metrics`` section a run's has, every row in one breakdown: the
    scorer's declared metrics (``Scorer.metrics``) over the fields it gives each point
    (``Scorer.point_fields``), through the function ``run`` and ``rescore`` use."""
    scored = list(scored)
    out = breakdown(
        ScoredRow(
            s.condition, s.direction, s.score.answered, s.score.l2, s.score.gt_in_frame, s.score.l2_strict, s.run,
            s.score.error_x, s.score.error_y, s.parse_error,
        )
        for s in scored
    )
    declared: Declared = {name: tuple(scorer.metrics) for name, scorer in (scorers or {}).items()}
    if any(declared.values()):
        rows = (
            _ScoredAsRow(
                "answered" if s.score.answered else "unanswered",
                {name: scorer.point_fields(s.score, s.l2_closest) for name, scorer in (scorers or {}).items()},
                s.condition,
                s.direction,
            )
            for s in scored
        )
        out["metrics"] = metrics_breakdown((valued_row(row, declared) for row in rows), declared)
    return out

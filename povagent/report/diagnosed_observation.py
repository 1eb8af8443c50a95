"""An answered row's error diagnosis as the report's observation holds it.

The fields of the scorers that declare a diagnosis (``Scorer.diagnosis``: the step an answer
failed at and whether it fell nearer the egocentric or the mirrored reading; whether it
satisfies the sentence's relation), read as the row stored them, never recomputed; the summary
reads them the same way (:func:`povagent.run.summary_fields.diagnosed_row`).
"""

from __future__ import annotations

from typing import Any

from povagent.results.rows import ResultRow
from povagent.scoring.score_protocols import diagnosing_scorers


def _uv(value: Any) -> tuple[float, float] | None:
    ok = isinstance(value, (list, tuple)) and len(value) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    return (float(value[0]), float(value[1])) if ok else None


def diagnosis_of(row: ResultRow, error_scorer: str | None) -> dict[str, Any]:
    """An answered row's diagnosing scorers' fields (``Scorer.diagnosis``) as :class:`Observation` fields
    (read as stored, never recomputed; ``{}`` when neither scored it); ``error_scorer`` is the
    run's ``normalized_l2`` scorer."""
    from povagent.run.summary_fields import diagnosed_row

    diagnosed = diagnosed_row(row, error_scorer)
    if diagnosed is None:
        return {}
    fields = row.scores.get(diagnosing_scorers().get("failure_step", "")) or {}
    return {
        "fail_step": diagnosed.step,
        "egocentric_uv": _uv(fields.get("egocentric")),
        "mirrored_uv": _uv(fields.get("mirrored")),
        "nearer_egocentric": diagnosed.nearer_egocentric,
        "relation": diagnosed.relation,
    }

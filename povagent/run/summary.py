"""Run summaries: ``summary.json``'s breakdown of a run's rows, from compact row digests.

The runner keeps one :class:`RowDigest` per key (rows of earlier sessions read once at resume,
its own rows as they become durable), so writing the summary never parses ``results.jsonl``
again; :func:`summarize_run` reads a finished folder for everyone else.
"""

from __future__ import annotations

import json
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

from povagent.results.rows import ResultRow, RowStatus, iter_rows
from povagent.scoring.breakdown import ScoredRow, breakdown, summarize


def scored_row(row: ResultRow, scorer: str = "official") -> ScoredRow:
    """The fields a summary needs, from a row's official score (non-answers count as such)."""
    score = row.scores.get(scorer) or {}
    answered = row.status is RowStatus.ANSWERED and bool(score.get("answered"))
    return ScoredRow(
        condition=row.condition,
        direction=row.direction,
        answered=answered,
        l2=score.get("l2") if answered else None,
        gt_in_frame=score.get("gt_in_frame") if answered else None,
        l2_strict=score.get("l2_strict") if answered else None,
        run=row.run,
    )


@dataclass(frozen=True, slots=True)
class RowDigest:
    """The few fields of a row that ``summary.json`` needs.

    The runner keeps one per key (rows of earlier sessions read once at resume, its own rows as
    they become durable), so writing the summary never parses ``results.jsonl`` again.
    """

    key: str
    run: int
    status: str
    scored: ScoredRow
    has_success: bool
    success: Any
    answered: bool
    prompt_tokens: int | None
    completion_tokens: int | None
    cost_usd: float | None
    retries: int


def digest(row: ResultRow) -> RowDigest:
    """The summary fields of one row."""
    success = row.scores.get("success")
    return RowDigest(
        key=row.key,
        run=row.run,
        status=RowStatus(row.status).value,
        scored=scored_row(row),
        has_success=success is not None,
        success=(success or {}).get("success"),
        # a row the runner never scored (parse or infra error) is unanswered
        answered=(success or {}).get("answered") is True,
        prompt_tokens=row.prompt_tokens,
        completion_tokens=row.completion_tokens,
        cost_usd=row.cost_usd,
        retries=row.retries,
    )


def summarize_digests(digests: Iterable[RowDigest], keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of row digests.

    ``keys`` is the run's selection (``rows`` then counts missing keys); digests of other keys
    are left out.
    """
    rows = [d for d in digests if keys is None or d.key in keys]
    scored = [d.scored for d in rows]
    out = breakdown(scored)
    if any(d.has_success for d in rows):
        from povagent.dataset.realworld import success_breakdown

        out["success"] = success_breakdown(
            {"condition": d.scored.condition, "direction": d.scored.direction, "success": d.success, "answered": d.answered}
            for d in rows
        )
    per_run: dict[int, list[ScoredRow]] = {}
    for d in rows:
        per_run.setdefault(d.run, []).append(d.scored)
    out["per_run"] = {str(k): summarize(v) for k, v in sorted(per_run.items())}
    statuses = Counter(d.status for d in rows)
    costs = [d.cost_usd for d in rows if d.cost_usd is not None]
    out["rows"] = {
        "total": len(keys) if keys is not None else len(rows),
        "done": len(rows),
        "missing": (len(keys) - len(rows)) if keys is not None else 0,
        **{s.value: statuses.get(s.value, 0) for s in RowStatus},
    }
    out["usage"] = {
        "prompt_tokens": sum(d.prompt_tokens or 0 for d in rows),
        "completion_tokens": sum(d.completion_tokens or 0 for d in rows),
        "cost_usd": sum(costs) if costs else None,
        "retries": sum(d.retries for d in rows),
    }
    return out


def summarize_run(results: Path, keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction) of a results file, per run too.

    ``keys`` restricts it to a run's selection; ``rows`` counts statuses and missing keys.
    When a key repeats, its last row counts.
    """
    by_key: dict[str, RowDigest] = {}
    for row in iter_rows(results):
        if keys is None or row.key in keys:
            by_key[row.key] = digest(row)
    return summarize_digests(by_key.values(), keys)


def write_json(path: Path, data: Mapping[str, Any]) -> None:
    """Write ``data`` as indented JSON, atomically (a kill leaves the old file or the new one)."""
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=2, default=str) + "\n", encoding="utf-8")
    os.replace(tmp, path)

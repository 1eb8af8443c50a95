"""Run summaries: ``summary.json``'s breakdown of a run's rows, from compact row digests.

The runner keeps one :class:`RowDigest` per key (rows of earlier sessions read once at resume,
its own rows as they become durable), so writing the summary never parses ``results.jsonl``
again; :func:`summarize_run` reads a finished folder for everyone else.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

from povagent.results.official_reading import nan_rows, official_parse_breakdown, officially_read
from povagent.results.rows import ResultRow, RowStatus, iter_rows
from povagent.scoring.breakdown import ScoredRow, breakdown, summarize
from povagent.scoring.diagnostics_breakdown import DiagnosedRow, diagnostics_breakdown


def scored_row(row: ResultRow, scorer: str = "official") -> ScoredRow:
    """The fields a summary needs, from a row's official score (non-answers count as such)."""
    from povagent.scoring.evaluations import official_parse_error

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
        error_x=score.get("error_x") if answered else None,
        error_y=score.get("error_y") if answered else None,
        parse_error=official_parse_error(row) is not None,
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
    #: The official reading's fields, for a row parsed leniently (``None``: no separate reading).
    official: ScoredRow | None = None
    official_parser: str | None = None
    #: The row's (official) parse holds a NaN coordinate: the official mean holding it is NaN.
    nan_coordinate: bool = False
    #: The true/false and number fields of every plugin scorer's scores (``summary.json``'s ``scorers``).
    plugin_scores: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()
    #: The ``diagnose`` and ``relation`` scores' fields (``summary.json``'s ``diagnostics``);
    #: ``None`` when neither scored the row.
    diagnosed: DiagnosedRow | None = None


#: Scorers whose fields ``summary.json`` breaks down in sections of their own.
_OWN_SECTIONS = frozenset({"official", "success"})


def plugin_scores(scores: Mapping[str, Any]) -> tuple[tuple[str, tuple[tuple[str, float], ...]], ...]:
    """For every other scorer of a row, its true/false and number fields (text and lists left out)."""
    return tuple(
        (name, tuple((k, v) for k, v in fields.items() if isinstance(v, (bool, int, float))))
        for name, fields in sorted(scores.items())
        if name not in _OWN_SECTIONS and isinstance(fields, Mapping)
    )


def plugin_score_summary(rows: Iterable[RowDigest]) -> dict[str, dict[str, dict[str, Any]]]:
    """``{scorer: {field: ...}}`` over the rows a plugin scorer scored (answered rows): a
    true/false field as ``{"n", "true", "rate"}``, a number as ``{"n", "mean"}``."""
    values: dict[str, dict[str, list[float]]] = {}
    for row in rows:
        for name, fields in row.plugin_scores:
            for key, value in fields:
                values.setdefault(name, {}).setdefault(key, []).append(value)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for name, by_field in values.items():
        out[name] = {}
        for key, vs in by_field.items():
            if all(isinstance(v, bool) for v in vs):
                out[name][key] = {"n": len(vs), "true": sum(vs), "rate": sum(vs) / len(vs)}
            elif not any(isinstance(v, bool) for v in vs):
                out[name][key] = {"n": len(vs), "mean": sum(vs) / len(vs)}
    return out


def digest(row: ResultRow) -> RowDigest:
    """The summary fields of one row."""
    success = row.scores.get("success")
    official_view = officially_read(row)  # the row itself when it holds no separate reading
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
        official=scored_row(official_view) if row.official_reading is not None else None,
        official_parser=row.official_reading.parser if row.official_reading is not None else None,
        nan_coordinate=bool(nan_rows([official_view])),
        plugin_scores=plugin_scores(row.scores),
        diagnosed=diagnosed_row(row),
    )


def diagnosed_row(row: ResultRow) -> DiagnosedRow | None:
    """The ``diagnose`` and ``relation`` fields of an answered row (``None`` when neither scored it)."""
    if row.status != RowStatus.ANSWERED:  # a StrEnum: a plain string from model_construct compares too
        return None
    diagnose = row.scores.get("diagnose")
    relation = row.scores.get("relation")
    diagnose = diagnose if isinstance(diagnose, Mapping) and diagnose.get("answered") is True else None
    relation = relation if isinstance(relation, Mapping) and relation.get("answered") is True else None
    if diagnose is None and relation is None:
        return None
    official = row.scores.get("official") or {}
    l2 = official.get("l2") if isinstance(official, Mapping) else None
    step = diagnose.get("step") if diagnose is not None else None
    vote = diagnose.get("nearer_egocentric") if diagnose is not None else None
    hit = relation.get("success") if relation is not None else None
    return DiagnosedRow(
        instance_id=row.instance_id,
        condition=str(row.condition),
        direction=str(row.direction),
        l2=float(l2) if isinstance(l2, (int, float)) and not isinstance(l2, bool) else None,
        step=step if isinstance(step, str) else None,
        nearer_egocentric=vote if isinstance(vote, bool) else None,
        relation=hit if isinstance(hit, bool) else None,
    )


def summarize_digests(digests: Iterable[RowDigest], keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of row digests.

    ``keys`` is the run's selection (``rows`` then counts missing keys); digests of other keys
    are left out.
    """
    rows = [d for d in digests if keys is None or d.key in keys]
    scored = [d.scored for d in rows]
    out = breakdown(scored)
    official_parser = next((d.official_parser for d in rows if d.official_parser), None)
    # parsed leniently: the paper-comparable reading beside it (official metric only: a
    # real-world set's success scorer has no official numbers to compare)
    if official_parser is not None and not any(d.has_success for d in rows):
        # a row with an answer but no reading (written before readings were recorded) is left
        # out and counted, never counted with its repaired parse
        unread = [d for d in rows if d.official is None and d.status != RowStatus.INFRA_ERROR.value]
        out["official_parse"] = official_parse_breakdown(
            [d.official if d.official is not None else d.scored for d in rows
             if d.official is not None or d.status == RowStatus.INFRA_ERROR.value],
            official_parser,
            len(unread),
        )  # fmt: skip
    if any(d.has_success for d in rows):
        from povagent.dataset.realworld import success_breakdown

        out["success"] = success_breakdown(
            {"condition": d.scored.condition, "direction": d.scored.direction, "success": d.success, "answered": d.answered}
            for d in rows
        )
    by_plugin = plugin_score_summary(rows)
    if by_plugin:  # a plugin scorer's own fields: what its author looks for first
        out["scorers"] = by_plugin
    diagnostics = diagnostics_breakdown(d.diagnosed for d in rows if d.diagnosed is not None)
    if diagnostics is not None:  # an addition, beside the official breakdown
        out["diagnostics"] = diagnostics
    nan_keys = [d.key for d in rows if d.nan_coordinate]
    if nan_keys:  # degenerate as officially: named, so a NaN mean is never a mystery
        out["nan_coordinate_rows"] = nan_keys
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


def write_json(path: Path, data: Mapping[str, Any], root: Path | None = None) -> None:
    """Write ``data`` as indented JSON, atomically (a kill leaves the old file or the new one).

    Written aside and renamed, never through a link planted at ``path`` or in a folder between
    ``root`` (the folder the user named; default ``path``'s own) and it; a full disk leaves the
    old file and no half-written copy beside it (see :mod:`povagent.run.confined_write`).
    """
    from povagent.run.confined_write import write_inside

    base = root if root is not None else path.parent
    write_inside(base, path.relative_to(base), json.dumps(data, indent=2, default=str) + "\n")

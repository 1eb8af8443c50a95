"""Run summaries: ``summary.json``'s breakdown of a run's rows (:class:`ResultRow`, one per key).

The runner keeps each key's row without its exchanges (:func:`summary_row`; rows of earlier
sessions read once at resume, its own rows as they become durable), so writing the summary
never parses ``results.jsonl`` again; :func:`summarize_run` reads a finished folder for
everyone else. :mod:`povagent.run.summary_model` says what the summary is.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from povagent.exchange.usage_totals import UsageTotals
from povagent.results.official_reading import nan_rows, official_parse_breakdown, officially_read
from povagent.results.output_check import check_output_text
from povagent.results.rows import ResultRow, RowStatus, iter_rows
from povagent.results.summary_json import summary_json_text
from povagent.run.summary_model import RunSummary
from povagent.scoring.breakdown import ScoredRow, breakdown, summarize
from povagent.scoring.diagnostics_breakdown import DiagnosedRow, diagnostics_breakdown
from povagent.scoring.metrics import Metric, metrics_breakdown, valued_row


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


#: Scorers whose fields ``summary.json`` breaks down in sections of their own.
_OWN_SECTIONS = frozenset({"official", "success"})


def plugin_scores(scores: Mapping[str, Any]) -> tuple[tuple[str, tuple[tuple[str, float], ...]], ...]:
    """For every other scorer of a row, its true/false and number fields (text and lists left out)."""
    return tuple(
        (name, tuple((k, v) for k, v in fields.items() if isinstance(v, (bool, int, float))))
        for name, fields in sorted(scores.items())
        if name not in _OWN_SECTIONS and isinstance(fields, Mapping)
    )


def plugin_score_summary(rows: Iterable[ResultRow]) -> dict[str, dict[str, dict[str, Any]]]:
    """``{scorer: {field: ...}}`` over the rows a plugin scorer scored (answered rows): a
    true/false field as ``{"n", "true", "rate"}``, a number as ``{"n", "mean"}``."""
    values: dict[str, dict[str, list[float]]] = {}
    for row in rows:
        for name, fields in plugin_scores(row.scores):
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


def summary_row(row: ResultRow) -> ResultRow:
    """The row as a summary keeps it: without its exchanges (prompts and raw answers, which no
    summary reads and which are most of a row's size). The runner keeps one per key (rows of
    earlier sessions read once at resume, its own rows as they become durable), so writing the
    summary never parses ``results.jsonl`` again."""
    return row.model_copy(update={"exchanges": []}) if row.exchanges else row


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


def summarize_rows(
    rows: Iterable[ResultRow], keys: set[str] | None = None, declared: Mapping[str, Sequence[Metric]] | None = None
) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of rows, one per key.

    ``keys`` is the run's selection (``rows`` then counts missing keys); rows of other keys
    are left out. ``declared`` is each scorer's metrics (``Scorer.metrics``): the ``metrics``
    section holds them per slice (see :mod:`povagent.scoring.metrics`).
    """
    rows = [r for r in rows if keys is None or r.key in keys]
    scored = [scored_row(r) for r in rows]
    out = breakdown(scored)
    official_parser = next((r.official_reading.parser for r in rows if r.official_reading is not None), None)
    with_success = [r for r in rows if r.scores.get("success") is not None]
    # parsed leniently: the paper-comparable reading beside it (official metric only: a
    # real-world set's success scorer has no official numbers to compare)
    if official_parser is not None and not with_success:
        # a row with an answer but no reading (written before readings were recorded) is left
        # out and counted, never counted with its repaired parse
        unread = [r for r in rows if r.official_reading is None and RowStatus(r.status) is not RowStatus.INFRA_ERROR]
        out["official_parse"] = official_parse_breakdown(
            [scored_row(officially_read(r)) for r in rows
             if r.official_reading is not None or RowStatus(r.status) is RowStatus.INFRA_ERROR],
            official_parser,
            len(unread),
        )  # fmt: skip
    if with_success:
        from povagent.dataset.realworld import success_breakdown

        def success_of(row: ResultRow) -> dict[str, Any]:
            success = row.scores.get("success") or {}
            # a row the runner never scored (parse or infra error) is unanswered
            return {"condition": row.condition, "direction": row.direction, "success": success.get("success"),
                    "answered": success.get("answered") is True}  # fmt: skip

        out["success"] = success_breakdown(success_of(r) for r in rows)
    if declared and any(declared.values()):
        out["metrics"] = metrics_breakdown((valued_row(r, declared) for r in rows), declared)
    by_plugin = plugin_score_summary(rows)
    if by_plugin:  # a plugin scorer's own fields: what its author looks for first
        out["scorers"] = by_plugin
    diagnostics = diagnostics_breakdown(d for d in (diagnosed_row(r) for r in rows) if d is not None)
    if diagnostics is not None:  # an addition, beside the official breakdown
        out["diagnostics"] = diagnostics
    nan_keys = [r.key for r in rows if nan_rows([officially_read(r)])]
    if nan_keys:  # degenerate as officially: named, so a NaN mean is never a mystery
        out["nan_coordinate_rows"] = nan_keys
    per_run: dict[int, list[ScoredRow]] = {}
    for row, one in zip(rows, scored):
        per_run.setdefault(row.run, []).append(one)
    out["per_run"] = {str(k): summarize(v) for k, v in sorted(per_run.items())}
    statuses = Counter(RowStatus(r.status).value for r in rows)
    out["rows"] = {
        "total": len(keys) if keys is not None else len(rows),
        "done": len(rows),
        "missing": (len(keys) - len(rows)) if keys is not None else 0,
        **{s.value: statuses.get(s.value, 0) for s in RowStatus},
    }
    spent = UsageTotals.of(rows, unstated_tokens=0)
    out["usage"] = {
        "prompt_tokens": spent.prompt_tokens,
        "completion_tokens": spent.completion_tokens,
        "cost_usd": spent.cost_usd,
        "retries": spent.retries,
    }
    return out


def declared_metrics(scorers: Mapping[str, Any]) -> dict[str, tuple[Metric, ...]]:
    """``{name: metrics}`` of scorer objects (or factories): what each declared."""
    return {name: tuple(getattr(scorer, "metrics", ())) for name, scorer in scorers.items()}


def summarize_run(results: Path, keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction) of a results file, per run too.

    ``keys`` restricts it to a run's selection; ``rows`` counts statuses and missing keys.
    When a key repeats, its last row counts.
    """
    by_key: dict[str, ResultRow] = {}
    for row in iter_rows(results):
        if keys is None or row.key in keys:
            by_key[row.key] = summary_row(row)
    return summarize_rows(by_key.values(), keys)


def write_summary(path: Path, data: Mapping[str, Any], root: Path | None = None) -> RunSummary:
    """Write a run's (or a rescore's) ``summary.json`` and return it read as the
    :class:`RunSummary` it is.

    It is read before it is written: a summary that is not a :class:`RunSummary` (a povagent
    bug) raises, and nothing is written; while tests run it is also checked against the shipped
    schema (:mod:`povagent.results.output_check`). Written as indented JSON, atomically (a kill
    leaves the old file or the new one); a number that is not finite (a NaN answer's margin) is
    ``null``, so the file is always JSON. Written aside and renamed, never through a link planted
    at ``path`` or in a folder between ``root`` (the folder the user named; default ``path``'s
    own) and it; a full disk leaves the old file and no half-written copy beside it (see
    :mod:`povagent.run.confined_write`).
    """
    from povagent.run.confined_write import write_inside

    summary = RunSummary.model_validate(data)
    text = summary_json_text(data, indent=2, default=str)
    check_output_text("summary", text, path)
    base = root if root is not None else path.parent
    write_inside(base, path.relative_to(base), text + "\n")
    return summary

"""Run summaries: ``summary.json``'s breakdown of a run's rows (:class:`ResultRow`, one per key).

The runner keeps each key's :class:`SummaryDigest` (:func:`summary_digest`: the few values a
summary reads of a row, a few hundred bytes; rows of earlier sessions read once at resume, its
own rows as they become durable), so writing the summary never parses ``results.jsonl`` again
and a run's memory hardly grows with its rows; :func:`summarize_run` reads a finished folder
for everyone else, and :func:`summarize_rows` summarizes rows in hand: all three through
:func:`summarize_digests`. :mod:`povagent.run.summary_model` says what the summary is.
"""

from __future__ import annotations

import sys
from collections import Counter
from dataclasses import dataclass
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
from povagent.scoring.metrics import Declared, Metric, MetricValues, ValuedRow, metrics_breakdown, row_category, row_metric_groups
from povagent.scoring.protocols import diagnosing_scorers, following, registered_protocols


def scored_row(row: ResultRow, scorer: str | None) -> ScoredRow:
    """The fields a summary needs, from the row's score by ``scorer``, the run's ``normalized_l2``
    scorer (non-answers count as such; ``None``: the run has none, and no row is answered)."""
    from povagent.scoring.evaluations import official_parse_error

    score = (row.scores.get(scorer) if scorer is not None else None) or {}
    answered = row.status is RowStatus.ANSWERED and bool(score.get("answered"))
    return ScoredRow(
        condition=sys.intern(row.condition),  # one string per label, not one per row a summary keeps
        direction=sys.intern(row.direction),
        answered=answered,
        l2=score.get("l2") if answered else None,
        gt_in_frame=score.get("gt_in_frame") if answered else None,
        l2_strict=score.get("l2_strict") if answered else None,
        run=row.run,
        error_x=score.get("error_x") if answered else None,
        error_y=score.get("error_y") if answered else None,
        parse_error=official_parse_error(row) is not None,
    )


def plugin_scores(scores: Mapping[str, Any], protocols: Mapping[str, str]) -> tuple[tuple[str, tuple[tuple[str, float], ...]], ...]:
    """For every scorer of a row that follows no protocol (``protocols``: ``{scorer: protocol}``;
    a protocol's fields have sections of their own), its true/false and number fields (text and
    lists left out)."""
    return tuple(
        (name, tuple((k, v) for k, v in fields.items() if isinstance(v, (bool, int, float))))
        for name, fields in sorted(scores.items())
        if name not in protocols and isinstance(fields, Mapping)
    )


def plugin_score_summary(rows: Iterable[ResultRow], protocols: Mapping[str, str] | None = None) -> dict[str, dict[str, dict[str, Any]]]:
    """``{scorer: {field: ...}}`` over the rows a plugin scorer scored (answered rows): a
    true/false field as ``{"n", "true", "rate"}``, a number as ``{"n", "mean"}``."""
    known = registered_protocols() if protocols is None else protocols
    return _plugin_score_summary(plugin_scores(row.scores, known) for row in rows)


def _plugin_score_summary(
    per_row: Iterable[tuple[tuple[str, tuple[tuple[str, float], ...]], ...]],
) -> dict[str, dict[str, dict[str, Any]]]:
    values: dict[str, dict[str, list[float]]] = {}
    for scores in per_row:
        for name, fields in scores:
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


@dataclass(frozen=True, slots=True)
class SummaryDigest:
    """What a summary reads of one row, taken once when the row is made or read: the row's
    ``normalized_l2`` score, its official reading's (lenient parsers), the ``marked_hit``
    scorer's verdict, the other scorers' fields, the diagnostics, whether it holds a NaN coordinate, and what it
    spent. Slotted and without the row's text (prompts, answers, sentence): a run keeps one
    per key."""

    key: str
    run: int
    status: str
    scored: ScoredRow
    #: the parser whose official reading the row records (``None``: it records none)
    official_parser: str | None
    #: the row as its official reading scores it (rows with a reading, and failed requests)
    officially_scored: ScoredRow | None
    #: ``(condition, direction, success, answered)`` when a ``marked_hit`` scorer scored the row
    success: tuple[str, str, Any, bool] | None
    plugin_scores: tuple[tuple[str, tuple[tuple[str, float], ...]], ...]
    diagnosed: DiagnosedRow | None
    has_nan: bool
    prompt_tokens: int | None
    completion_tokens: int | None
    cost_usd: float | None
    retries: int
    #: the row's value of every declared metric (:func:`~povagent.scoring.metrics.row_metric_values`),
    #: flat in the declared order, scorer by scorer (the names are the declaration's: one tuple
    #: per key, not a pair per value); empty when no metrics were declared
    metric_values: tuple[float | None, ...] = ()
    #: the question's category and the groups of grouped metrics (a multiple-choice row's;
    #: :func:`~povagent.scoring.metrics.valued_row`)
    category: str | None = None
    metric_groups: Mapping[str, Mapping[str, str]] | None = None


def summary_digest(row: ResultRow, declared: Declared | None = None, protocols: Mapping[str, str] | None = None) -> SummaryDigest:
    """The row as a summary keeps it (see :class:`SummaryDigest`), with its values of the
    ``declared`` metrics; ``protocols`` says which of the run's scorers follows which protocol
    (``{scorer: protocol}``; default: as the registered scorers declare)."""
    protocols = registered_protocols() if protocols is None else protocols
    error_scorer = following(protocols, "normalized_l2", row.scores)
    hit_scorer = following(protocols, "marked_hit", row.scores)
    infra = RowStatus(row.status) is RowStatus.INFRA_ERROR
    reading = row.official_reading
    official = officially_read(row)
    success = row.scores.get(hit_scorer) if hit_scorer is not None else None
    scored = scored_row(row, error_scorer)
    officially_scored = scored_row(official, error_scorer) if reading is not None or infra else None
    if officially_scored == scored:
        officially_scored = scored  # read the same way (the usual case): one object, not two
    return SummaryDigest(
        key=row.key,
        run=row.run,
        status=sys.intern(RowStatus(row.status).value),
        scored=scored,
        official_parser=None if reading is None else sys.intern(reading.parser),
        officially_scored=officially_scored,
        success=None if success is None else (
            sys.intern(row.condition), sys.intern(row.direction), (success or {}).get("success"), (success or {}).get("answered") is True
        ),
        plugin_scores=plugin_scores(row.scores, protocols),
        diagnosed=diagnosed_row(row, error_scorer),
        has_nan=bool(nan_rows([official])),
        prompt_tokens=row.prompt_tokens,
        completion_tokens=row.completion_tokens,
        cost_usd=row.cost_usd,
        retries=row.retries,
        metric_values=MetricValues.of(row, declared).flat if declared else (),
        category=row_category(row),
        metric_groups=(row_metric_groups(row, declared) or None) if declared else None,
    )


def diagnosed_row(row: ResultRow, error_scorer: str | None) -> DiagnosedRow | None:
    """The fields of the scorers diagnosing an answered row (``failure_step`` and
    ``relation_hit``, :func:`~povagent.scoring.protocols.diagnosing_scorers`), with its error by
    ``error_scorer`` (the run's ``normalized_l2`` scorer), or ``None`` when neither scored it."""
    if row.status != RowStatus.ANSWERED:  # a StrEnum: a plain string from model_construct compares too
        return None
    by = diagnosing_scorers()
    diagnose = row.scores.get(by.get("failure_step", ""))
    relation = row.scores.get(by.get("relation_hit", ""))
    diagnose = diagnose if isinstance(diagnose, Mapping) and diagnose.get("answered") is True else None
    relation = relation if isinstance(relation, Mapping) and relation.get("answered") is True else None
    if diagnose is None and relation is None:
        return None
    official = (row.scores.get(error_scorer) if error_scorer is not None else None) or {}
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
    rows: Iterable[ResultRow],
    keys: set[str] | None = None,
    declared: Mapping[str, Sequence[Metric]] | None = None,
    protocols: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of rows, one per key.

    ``keys`` is the run's selection (``rows`` then counts missing keys); rows of other keys
    are left out. ``declared`` is each scorer's metrics (``Scorer.metrics``): the ``metrics``
    section holds them per slice (see :mod:`povagent.scoring.metrics`); ``protocols`` says which
    scorer follows which protocol (see :func:`summary_digest`).
    """
    protocols = registered_protocols() if protocols is None else protocols
    return summarize_digests((summary_digest(r, declared, protocols) for r in rows if keys is None or r.key in keys), keys, declared)


def summarize_digests(
    digests: Iterable[SummaryDigest], keys: set[str] | None = None, declared: Mapping[str, Sequence[Metric]] | None = None
) -> dict[str, Any]:
    """:func:`summarize_rows` of the rows these digests were taken from (one per key), the digests
    taken with the same ``declared`` metrics."""
    rows = [d for d in digests if keys is None or d.key in keys]
    out = breakdown([d.scored for d in rows])
    official_parser = next((d.official_parser for d in rows if d.official_parser is not None), None)
    # every row counts once any row was scored by success: a row it never scored (a parse or
    # infra error) is an unanswered failure, as the paper counts it
    with_success = (
        [d.success or (d.scored.condition, d.scored.direction, None, False) for d in rows] if any(d.success is not None for d in rows) else []
    )
    # parsed leniently: the paper-comparable reading beside it (official metric only: a
    # real-world set's success scorer has no official numbers to compare)
    if official_parser is not None and not with_success:
        # a row with an answer but no reading (written before readings were recorded) is left
        # out and counted, never counted with its repaired parse
        unread = sum(1 for d in rows if d.official_parser is None and d.status != RowStatus.INFRA_ERROR.value)
        out["official_parse"] = official_parse_breakdown(
            [d.officially_scored for d in rows if d.officially_scored is not None], official_parser, unread
        )
    if with_success:
        from povagent.dataset.realworld import success_breakdown

        # a row the runner never scored (parse or infra error) is unanswered
        out["success"] = success_breakdown(
            {"condition": c, "direction": d, "success": hit, "answered": answered} for c, d, hit, answered in with_success
        )
    if declared and any(declared.values()):
        out["metrics"] = metrics_breakdown(
            (ValuedRow(d.scored.condition, d.scored.direction, MetricValues(d.metric_values, declared), d.category,
                       d.metric_groups or {}) for d in rows), declared
        )
    by_plugin = _plugin_score_summary(d.plugin_scores for d in rows)
    if by_plugin:  # a plugin scorer's own fields: what its author looks for first
        out["scorers"] = by_plugin
    diagnostics = diagnostics_breakdown(d.diagnosed for d in rows if d.diagnosed is not None)
    if diagnostics is not None:  # an addition, beside the official breakdown
        out["diagnostics"] = diagnostics
    nan_keys = [d.key for d in rows if d.has_nan]
    if nan_keys:  # degenerate as officially: named, so a NaN mean is never a mystery
        out["nan_coordinate_rows"] = nan_keys
    per_run: dict[int, list[ScoredRow]] = {}
    for d in rows:
        per_run.setdefault(d.run, []).append(d.scored)
    out["per_run"] = {str(k): summarize(v) for k, v in sorted(per_run.items())}
    statuses = Counter(d.status for d in rows)
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


def summarize_run(
    results: Path, keys: set[str] | None = None, declared: Mapping[str, Sequence[Metric]] | None = None,
    protocols: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction) of a results file, per run too.

    ``keys`` restricts it to a run's selection; ``rows`` counts statuses and missing keys.
    When a key repeats, its last row counts. ``declared`` and ``protocols``: as for
    :func:`summary_digest` (default: the registered scorers' protocols). The file is read one
    row at a time; only each key's digest is kept.
    """
    by_key: dict[str, SummaryDigest] = {}
    protocols = registered_protocols() if protocols is None else protocols
    for row in iter_rows(results):
        if keys is None or row.key in keys:
            by_key[row.key] = summary_digest(row, declared, protocols)
    return summarize_digests(by_key.values(), keys, declared)


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

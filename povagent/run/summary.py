"""Run summaries: ``summary.json``'s breakdown of a run's rows (:class:`ResultRow`, one per key).

A run keeps of each key only what its summary reads: a
:class:`~povagent.run.summary_table.SummaryTable` (the values a summary reads of each key's row,
in columns: under 200 bytes a key, so a run's memory hardly grows with its rows). A run whose
``results.jsonl`` started empty adds each row as it is written (:func:`written_rows_table`), so
its rows are read once; any other run reads the file back at its end (:func:`summarize_run`), a
row at a time. :func:`summarize_rows` summarizes rows in hand (a rescore's); all go through
:func:`summarize_table`. :mod:`povagent.run.summary_model` says what the
summary is; :mod:`povagent.run.summary_fields` what a summary reads of one row.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Collection, Iterable, Mapping, Sequence

from povagent.results.official_reading import official_parse_breakdown
from povagent.results.output_check import check_output_text
from povagent.results.rows import ResultRow, RowStatus, iter_rows
from povagent.results.summary_json import summary_json_text
from povagent.results.upgrade import FIELD, SUMMARY_FORMAT
from povagent.run.summary_model import RunSummary
from povagent.run.summary_table import SummaryTable
from povagent.scoring.breakdown import breakdown, summarize
from povagent.scoring.diagnostics_breakdown import diagnostics_breakdown
from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric


def _plugin_score_summary(
    per_row: Iterable[tuple[tuple[str, tuple[tuple[str, float], ...]], ...]],
) -> dict[str, dict[str, dict[str, Any]]]:
    values: dict[str, dict[str, list[float]]] = {}
    for scores in per_row:
        for name, fields in scores:
            # (looked up, not setdefault: its default is a new dict or list made at every value)
            by_field = values.get(name)
            if by_field is None:
                by_field = values[name] = {}
            for key, value in fields:
                kept = by_field.get(key)
                if kept is None:
                    kept = by_field[key] = []
                kept.append(value)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for name, by_field in values.items():
        out[name] = {}
        for key, vs in by_field.items():
            if all(isinstance(v, bool) for v in vs):
                out[name][key] = {"n": len(vs), "true": sum(vs), "rate": sum(vs) / len(vs)}
            elif not any(isinstance(v, bool) for v in vs):
                out[name][key] = {"n": len(vs), "mean": sum(vs) / len(vs)}
    return out


def summarize_rows(
    rows: Iterable[ResultRow],
    keys: Collection[str] | None = None,
    declared: Mapping[str, Sequence[Metric]] | None = None,
    protocols: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of rows, one per key.

    ``keys`` is the run's selection (``rows`` then counts missing keys); rows of other keys
    are left out. When a key repeats, its last row counts. The rows are summarized in one order
    whatever order they come in (their keys' digests: :mod:`povagent.run.summary_table`), so a run
    whose rows finished in any order, or was resumed, its file read back and a rescore of it have
    one summary, to the last bit (sums and bootstrap draws follow the rows' order). ``declared``
    is each scorer's metrics (``Scorer.metrics``): the ``metrics`` section holds them per slice (see
    :mod:`povagent.scoring.metrics`); ``protocols`` says which scorer follows which protocol
    (``{scorer: protocol}``; default: as the registered scorers declare). The rows are kept as
    a :class:`~povagent.run.summary_table.SummaryTable`: a few bytes a row.
    """
    table = SummaryTable(declared, protocols, keys)
    for row in rows:
        table.add(row)
    return summarize_table(table.close(), None if keys is None else len(keys))


def summarize_table(table: SummaryTable, n_keys: int | None = None) -> dict[str, Any]:
    """:func:`summarize_rows` of the rows ``table`` holds (closed); ``n_keys``: how many keys the
    run's selection has (``None``: as many as the table holds)."""
    scored = table.scored
    out = breakdown(scored)
    official_parser = table.official_parser()
    # every row counts once any row was scored by success: a row it never scored (a parse or
    # infra error) is an unanswered failure, as the paper counts it
    with_success = table.has_success()
    # parsed leniently: the paper-comparable reading beside it (official metric only: a
    # real-world set's success scorer has no official numbers to compare)
    if official_parser is not None and not with_success:
        # a row with an answer but no reading (a format 0 row: povagent.results.upgrade) is left
        # out and counted, never counted with its repaired parse
        same = out if table.read_as_scored() else None  # the same rows, scored the same: the same breakdown
        out["official_parse"] = official_parse_breakdown(table.officially_scored(), official_parser, table.unread(), same)
    if with_success:
        from povagent.dataset.realworld_set import success_breakdown

        out["success"] = success_breakdown(table.success_rows())
    if table.metrics.declared:
        out["metrics"] = metrics_breakdown(table.metrics, table.declared)
    by_plugin = _plugin_score_summary(table.plugin_scores())
    if by_plugin:  # a plugin scorer's own fields: what its author looks for first
        out["scorers"] = by_plugin
    diagnostics = diagnostics_breakdown(table.diagnosed())
    if diagnostics is not None:  # an addition, beside the official breakdown
        out["diagnostics"] = diagnostics
    nan_keys = table.nan_keys()
    if nan_keys:  # degenerate as officially: named, so a NaN mean is never a mystery
        out["nan_coordinate_rows"] = nan_keys
    if "per_run" not in out:  # several runs: the breakdown has each run's overall cell already
        out["per_run"] = {str(k): summarize(v) for k, v in table.by_run().items()}
    statuses = table.statuses()
    out["rows"] = {
        "total": n_keys if n_keys is not None else len(table),
        "done": len(table),
        "missing": (n_keys - len(table)) if n_keys is not None else 0,
        **{s.value: statuses.get(s.value, 0) for s in RowStatus},
    }
    spent = table.usage()
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
    results: Path, keys: Collection[str] | None = None, declared: Mapping[str, Sequence[Metric]] | None = None,
    protocols: Mapping[str, str] | None = None, written: SummaryTable | None = None,
) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction) of a results file, per run too.

    ``keys`` restricts it to a run's selection; ``rows`` counts statuses and missing keys.
    When a key repeats, its last row counts. ``declared`` and ``protocols``: as for
    :func:`summarize_rows`. The file is read one row at a time, and kept in columns; unless
    ``written`` holds every row of the file already (:func:`written_rows_table`, made with the
    same ``keys``, ``declared`` and ``protocols``): then it is not read again.
    """
    if written is not None:
        return summarize_table(written.close(), None if keys is None else len(keys))
    return summarize_rows(iter_rows(results), keys, declared, protocols)


def written_rows_table(
    results: Path, keys: Collection[str] | None, declared: Mapping[str, Sequence[Metric]] | None, protocols: Mapping[str, str] | None
) -> SummaryTable | None:
    """A table to add a run's rows to as they are written, when ``results`` holds no row yet:
    the rows written are then the file's rows, in the file's order, and :func:`summarize_run`
    given the table reads the same values the file holds without reading it. ``None`` when the
    file has rows already (a resumed run: the file is read back at the end)."""
    if results.exists() and results.stat().st_size:
        return None
    return SummaryTable(declared, protocols, keys)


def write_summary(path: Path, data: Mapping[str, Any], root: Path | None = None) -> RunSummary:
    """Write a run's (or a rescore's) ``summary.json`` and return it read as the
    :class:`RunSummary` it is.

    It carries its format version first (``format_version``: :mod:`povagent.results.upgrade`).
    It is read before it is written: a summary that is not a :class:`RunSummary` (a povagent
    bug) raises, and nothing is written; while tests run it is also checked against the shipped
    schema (:mod:`povagent.results.output_check`). Written as indented JSON, atomically (a kill
    leaves the old file or the new one); a number that is not finite (a NaN answer's margin) is
    ``null``, so the file is always JSON. Written aside and renamed, never through a link planted
    at ``path`` or in a folder between ``root`` (the folder the user named; default ``path``'s
    own) and it; a full disk leaves the old file and no half-written copy beside it (see
    :mod:`povagent.files.confined_write`).
    """
    from povagent.files.confined_write import write_inside

    data = {FIELD: SUMMARY_FORMAT, **data}  # first: a reader sees the shape before the sections
    summary = RunSummary.model_validate(data)
    text = summary_json_text(data, indent=2, default=str)
    check_output_text("summary", text, path)
    base = root if root is not None else path.parent
    write_inside(base, path.relative_to(base), text + "\n")
    return summary

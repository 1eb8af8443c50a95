"""The console's table of a scorer's declared metrics (``summary.json``'s ``metrics`` section).

A scorer declares its numbers (:mod:`povagent.scoring.metrics`); this prints them per slice
(overall, each condition, each direction) with their 95% bootstrap CIs, one table per scorer,
whatever the scorer is: a third-party scorer's numbers reach the console without a line here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Iterable, Mapping

if TYPE_CHECKING:
    from povagent.cli.console_width import PathTitle
    from povagent.run.summary_model import MetricDeclaration, MetricEstimate, RunSummary, ScorerMetrics, ScoreSummary


def metric_cell(estimate: MetricEstimate | None, aggregation: str) -> str:
    """``0.412 [0.38, 0.44]``, a rate as a percentage; ``-`` when nothing was measured."""
    if estimate is None or estimate.value is None:
        return "-"

    def shown(v: float) -> str:
        return f"{100 * v:.1f}%" if aggregation == "rate" else f"{v:.3f}"

    ci = f" [{shown(estimate.ci_lo)}, {shown(estimate.ci_hi)}]" if estimate.ci_lo is not None and estimate.ci_hi is not None else ""
    return f"{shown(estimate.value)}{ci} n={estimate.n}"


def metrics_rows(metrics: ScorerMetrics, declared: Mapping[str, MetricDeclaration] | None = None) -> tuple[list[str], list[list[str]]]:
    """``(headers, rows)``: a column per declared metric (its label, arrow of the better
    direction; ``declared``: only these of them), a row per slice."""
    from povagent.cli.slice_rows import breakdown_slices

    declared = metrics.declared if declared is None else declared
    names = list(declared)
    headers = [f"{d.label} {'↓' if d.better == 'lower' else '↑'}" for d in declared.values()]
    rows = [[label, *(metric_cell(cell.get(n), declared[n].aggregation) for n in names)] for label, cell in breakdown_slices(metrics)]
    return headers, rows


def protocol_scorers(summary: RunSummary | ScoreSummary, protocol: str) -> list[str]:
    """The scorers of the summarized rows that follow ``protocol`` (``Scorer.protocol``): those
    the pipeline names, else those that declared metrics (a rescore), else, for a summary written
    before either was recorded, the pipeline's default scorers."""
    from povagent.config.pipeline import default_scorers
    from povagent.scoring.score_protocols import registered_protocols

    pipeline = getattr(summary, "pipeline", None)
    names = list(pipeline.scorers) if pipeline is not None else list(summary.metrics or {}) or default_scorers()
    known = registered_protocols()
    return [n for n in names if known.get(n) == protocol]


def render_metrics(summary: RunSummary | ScoreSummary, title: str | PathTitle, shown: Iterable[str] = ()) -> None:
    """Print a table per scorer in ``summary.metrics``; of a scorer in ``shown`` (whose protocol's
    table printed already) only the metrics that table does not show, if any
    (:func:`~povagent.scoring.score_protocols.beyond_protocol`)."""
    from rich.console import Console

    from povagent.cli.console_width import fitted_tables
    from povagent.scoring.score_protocols import beyond_protocol, registered_protocols

    skip = set(shown)
    protocols = registered_protocols() if skip else {}
    for scorer, metrics in (summary.metrics or {}).items():
        declared = beyond_protocol(metrics.declared, protocols.get(scorer)) if scorer in skip else metrics.declared
        if not declared:
            continue
        headers, rows = metrics_rows(metrics, declared)
        captions = "; ".join(f"{d.label}: {d.caption}" for d in declared.values())
        columns = [("slice", "label")] + [(h, "number") for h in headers]
        heading = f"{title}\nscorer {scorer}" if isinstance(title, str) else title._replace(after=f"{title.after}\nscorer {scorer}")
        for table in fitted_tables(columns, rows, title=heading, caption=captions):
            Console().print(table)

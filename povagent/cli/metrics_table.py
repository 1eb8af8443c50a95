"""The console's table of a scorer's declared metrics (``summary.json``'s ``metrics`` section).

A scorer declares its numbers (:mod:`povagent.scoring.metrics`); this prints them per slice
(overall, each condition, each direction) with their 95% bootstrap CIs, one table per scorer,
whatever the scorer is: a third-party scorer's numbers reach the console without a line here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Iterable

if TYPE_CHECKING:
    from povagent.cli.console_width import PathTitle
    from povagent.run.summary_model import MetricEstimate, RunSummary, ScorerMetrics, ScoreSummary


def metric_cell(estimate: MetricEstimate | None, aggregation: str) -> str:
    """``0.412 [0.38, 0.44]``, a rate as a percentage; ``-`` when nothing was measured."""
    if estimate is None or estimate.value is None:
        return "-"

    def shown(v: float) -> str:
        return f"{100 * v:.1f}%" if aggregation == "rate" else f"{v:.3f}"

    ci = f" [{shown(estimate.ci_lo)}, {shown(estimate.ci_hi)}]" if estimate.ci_lo is not None and estimate.ci_hi is not None else ""
    return f"{shown(estimate.value)}{ci} n={estimate.n}"


def metrics_rows(metrics: ScorerMetrics) -> tuple[list[str], list[list[str]]]:
    """``(headers, rows)``: a column per declared metric (its label, arrow of the better
    direction), a row per slice."""
    from povagent.cli.slice_rows import breakdown_slices

    names = list(metrics.declared)
    headers = [f"{d.label} {'↓' if d.better == 'lower' else '↑'}" for d in metrics.declared.values()]
    rows = [[label, *(metric_cell(cell.get(n), metrics.declared[n].aggregation) for n in names)] for label, cell in breakdown_slices(metrics)]
    return headers, rows


def protocol_scorers(summary: RunSummary | ScoreSummary, protocol: str) -> list[str]:
    """The scorers of the summarized rows that follow ``protocol`` (``Scorer.protocol``): those
    the pipeline names, else those that declared metrics (a rescore), else, for a summary written
    before either was recorded, the pipeline's default scorers."""
    from povagent.config.pipeline import default_scorers
    from povagent.scoring.protocols import registered_protocols

    pipeline = getattr(summary, "pipeline", None)
    names = list(pipeline.scorers) if pipeline is not None else list(summary.metrics or {}) or default_scorers()
    known = registered_protocols()
    return [n for n in names if known.get(n) == protocol]


def render_metrics(summary: RunSummary | ScoreSummary, title: str | PathTitle, shown: Iterable[str] = ()) -> None:
    """Print a table per scorer in ``summary.metrics`` not in ``shown`` (scorers whose numbers
    a table of their own already printed)."""
    from rich.console import Console

    from povagent.cli.console_width import fitted_tables

    skip = set(shown)
    for scorer, metrics in (summary.metrics or {}).items():
        if scorer in skip:
            continue
        headers, rows = metrics_rows(metrics)
        captions = "; ".join(f"{d.label}: {d.caption}" for d in metrics.declared.values())
        columns = [("slice", "label")] + [(h, "number") for h in headers]
        heading = f"{title}\nscorer {scorer}" if isinstance(title, str) else title._replace(after=f"{title.after}\nscorer {scorer}")
        for table in fitted_tables(columns, rows, title=heading, caption=captions):
            Console().print(table)

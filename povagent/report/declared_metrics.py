"""The report's numbers of every declared metric: per scorer and system, overall and per slice.

A scorer declares its metrics (:mod:`povagent.scoring.metrics`); the runs' summaries record the
declarations (:attr:`povagent.results.finished_run.FinishedRun.declared`), and each observation
carries its row's values. This estimates each metric per system through the one estimate ``summary.json`` uses
(:func:`~povagent.scoring.metric_columns.metric_slices`), whatever the scorer, so the report's
tables and plots of a third party's metrics need no code of its own.

Pure numerics over observations: nothing here reads rows or writes files.
"""

from __future__ import annotations

from typing import Any, Mapping

from povagent.report.collect import Collection, Observation
from povagent.scoring.bootstrap import DRAWS_PER_BLOCK, Estimate
from povagent.scoring.metric_columns import MetricColumns, metric_slices
from povagent.scoring.metrics import Metric, ValuedRow


def declared_metric_estimates(
    collection: Collection, by_system: Mapping[str, list[Observation]], systems: list[str], n_boot: int, seed: int
) -> tuple[dict[str, dict[str, Metric]], dict[str, dict[str, dict[str, Any]]]]:
    """The metrics the runs' scorers declared, and per scorer and system each one's mean (a
    rate: of true values) with its bootstrap CI, overall and per slice (condition, direction),
    from the values each row's observation carries, through the one estimate ``summary.json``
    uses (:func:`~povagent.scoring.metric_columns.metric_slices`)."""
    declared: dict[str, dict[str, Metric]] = {}
    for run in collection.runs:
        for scorer, run_metrics in run.opened.declared.items():
            for m in run_metrics:
                declared.setdefault(scorer, {}).setdefault(m.name, m)
    estimates: dict[str, dict[str, dict[str, Any]]] = {}
    for scorer, metrics in declared.items():
        for system in systems:
            rows = MetricColumns.of(
                (ValuedRow(o.condition, o.direction, o.metric_values, o.category, o.metric_groups or {})
                 for o in by_system.get(system, []) if scorer in o.metric_values),
                {scorer: tuple(metrics.values())},
            )
            if len(rows):
                # half the shared block, as the report's other CIs: its draws and their gathered
                # values are the transient on top of every row the report holds
                estimates.setdefault(scorer, {})[system] = metric_slices(rows, scorer, n_boot, seed, DRAWS_PER_BLOCK // 2)
    return declared, estimates


def declared_estimates_json(estimates: Mapping[str, Mapping[str, Mapping[str, Any]]]) -> dict[str, Any]:
    """The estimates as the report's ``summary.json`` holds them: per scorer, system and slice,
    each metric's value, CI and count."""

    def cell(metrics: Mapping[str, Estimate]) -> dict[str, Any]:
        return {name: e.as_dict() for name, e in metrics.items()}

    return {
        scorer: {
            system: {"overall": cell(b["overall"]), **{k: {label: cell(c) for label, c in b[k].items()} for k in b if k != "overall"}}
            for system, b in by_system.items()
        }
        for scorer, by_system in estimates.items()
    }

"""The console's ``diagnostics`` table: why answers failed, printed under the official table.

An addition, labelled as such: the first failing step's shares, the egocentric-bias index with
its 95% CI and the relation-consistent success per condition, from ``summary.json``'s
``diagnostics`` section (:mod:`povagent.scoring.diagnostics_breakdown`). Nothing is printed
for a run scored without ``diagnose`` or ``relation``.
"""

from __future__ import annotations

from typing import Any

from povagent.scoring.diagnosis import STEPS

CONDITION_NAMES = {"a": "A Inferred", "b": "B Stated", "c": "C Given"}


def _pct(value: Any) -> str:
    return "-" if not isinstance(value, (int, float)) else f"{100 * value:.1f}%"


def diagnostics_rows(diagnostics: dict[str, Any]) -> list[list[str]]:
    """One row per condition: steps' shares, bias [CI] (n), relation success (n)."""
    rows = []
    for cond, cell in sorted((diagnostics.get("per_condition") or {}).items()):
        steps = cell.get("failure_steps") or {}
        bias = cell.get("egocentric_bias")
        ci = cell.get("egocentric_bias_ci")
        if isinstance(bias, (int, float)):
            bias_text = f"{bias:.2f}" + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "") + f" (n {cell.get('bias_n', 0)})"
        else:
            bias_text = "-"
        rows.append([
            CONDITION_NAMES.get(cond, cond),
            *(_pct(steps.get(s)) for s in STEPS),
            bias_text,
            f"{_pct(cell.get('relation_success'))} (n {cell.get('relation_n', 0)})",
        ])  # fmt: skip
    return rows


def render_diagnostics(summary: dict[str, Any]) -> None:
    """Print the ``diagnostics`` section of ``summary`` (nothing when it has none)."""
    diagnostics = summary.get("diagnostics")
    if not isinstance(diagnostics, dict):
        return
    from rich.console import Console

    from povagent.cli.console_width import fitted_table

    columns = [("condition", "label")] + [(s, "number") for s in STEPS] + [("ego. bias [95% CI]", "text"), ("relation success", "text")]
    Console().print(fitted_table(
        columns, diagnostics_rows(diagnostics),
        title="Additions (not in the paper): first failing step, egocentric bias, relation success",
        caption="shares of answered rows; bias: share nearer the egocentric target where the two differ (not for C); docs/diagnostics.md",
    ))  # fmt: skip

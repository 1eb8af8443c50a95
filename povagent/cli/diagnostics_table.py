"""The console's ``diagnostics`` table: why answers failed, printed under the official table.

An addition, labelled as such: the first failing step's shares, the egocentric-bias index with
its 95% CI and the relation-consistent success per condition, from ``summary.json``'s
``diagnostics`` section (:mod:`povagent.scoring.diagnostics_breakdown`). Nothing is printed
for a run scored without ``diagnose`` or ``relation``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from povagent.scoring.diagnosis import STEPS

if TYPE_CHECKING:
    from povagent.run.summary_model import DiagnosedCondition, Diagnostics, RunSummary


def _pct(value: Any) -> str:
    return "-" if not isinstance(value, (int, float)) else f"{100 * value:.1f}%"


CONDITION_NAMES = {"a": "Inferred (A)", "b": "Stated (B)", "c": "Given (C)"}


def diagnostics_rows(diagnostics: Diagnostics) -> tuple[list[str], list[list[str]]]:
    """``(conditions, rows)``: a row per failure step (share of answered rows), then the
    egocentric bias, its 95% CI, the answers it counts, and the relation success; a column per
    condition (a terminal has room for three columns, not for ten)."""
    cells = sorted(diagnostics.per_condition.items())
    rows = [[f"step: {s}", *(_pct(c.failure_steps.get(s)) for _, c in cells)] for s in STEPS]

    def bias(c: DiagnosedCondition) -> tuple[str, str, str]:
        value, ci = c.egocentric_bias, c.egocentric_bias_ci
        if value is None:
            return ("-", "-", "-")
        return (f"{value:.2f}", f"{ci[0]:.2f}-{ci[1]:.2f}" if ci else "-", str(c.bias_n))

    biases = [bias(c) for _, c in cells]
    rows.append(["egocentric bias", *(b[0] for b in biases)])
    rows.append(["  95% CI", *(b[1] for b in biases)])
    rows.append(["  answers counted", *(b[2] for b in biases)])
    rows.append(["relation success", *(_pct(c.relation_success) for _, c in cells)])
    return [CONDITION_NAMES.get(k, k) for k, _ in cells], rows


def render_diagnostics(summary: RunSummary) -> None:
    """Print the ``diagnostics`` section of ``summary`` (nothing when it has none)."""
    diagnostics = summary.diagnostics
    if diagnostics is None:
        return
    from rich.console import Console

    from povagent.cli.console_width import fitted_table

    conditions, rows = diagnostics_rows(diagnostics)
    Console().print(
        fitted_table(
            [("addition", "label"), *((c, "number") for c in conditions)],
            rows,
            title="Additions (not in the paper): why answers fail",
            caption="steps, relation success: shares of answered rows; egocentric bias: share nearer the egocentric "
            "target where it differs from the true one (not for C); docs/how-to/why-models-fail.md",
        )
    )

"""The paper's tables, built from an :class:`~povagent.report.analysis.Analysis`.

- ``main``: mean normalized L2 per system and condition (the paper's Table "main results");
- ``ablation``: strategy x condition with the response rate (only when strategies vary);
- ``per_direction`` and ``per_condition_direction``: errors by direction;
- ``response_rates``: answered / total per condition;
- ``metric_variants``: the official mean beside counting-non-responses, strict, and
  frame-selection accuracy (GT inside the selected frame);
- ``paired``: paired comparisons (mean difference with CI, Wilcoxon and sign tests).

The error tables follow the ``normalized_l2`` protocol (``Scorer.protocol``): they appear only
for rows a scorer following it scored. A real-world set (hand-marked ground truth, a
``marked_hit`` scorer) has no official error: its report has ``success`` (success rate per
system and condition, with the response rate) and ``success_by_direction`` instead, beside
``response_rates`` and ``paired``. Every other scorer gets a table per metric it declares
(``metric_<scorer>_<metric>``: per condition and overall, and by direction); the response rate
of a run scored by such scorers alone counts the rows whose status is ``answered``.

Only table assembly: numbers come from the analysis, text from :mod:`povagent.report.tables`.
"""

from __future__ import annotations

import re
from typing import Any, Callable

from povagent.dataset.release_models import Condition
from povagent.report.analysis import Analysis, SystemStats
from povagent.report.statistics import CellStats, Estimate
from povagent.report.tables import Cell, Column, Kind, Row, Table


def condition_label(c: str) -> str:
    """The paper's name of a condition code (``a`` -> Inferred); unknown codes pass through."""
    try:
        return Condition(c).label
    except ValueError:
        return c


def _cell(e: Estimate | None) -> Cell:
    if e is None:
        return Cell(None)
    return Cell(e.value, e.lo, e.hi)


def _pick(stats: dict[str, CellStats], key: str, number: Callable[[CellStats], Estimate]) -> Estimate | None:
    """One number of a slice's cell (``None``: the system has no row in the slice)."""
    cell = stats.get(key)
    return number(cell) if cell is not None else None


def cell_error(cell: CellStats) -> Estimate:
    """A cell's official mean L2."""
    return cell.official


def cell_hit(cell: CellStats) -> Estimate:
    """A cell's success rate."""
    return cell.success


def cell_response(cell: CellStats) -> Estimate:
    """A cell's response rate."""
    return cell.response_rate



PROTOCOL = (
    "Mean normalized L2 (lower is better) over answered instances, averaged over runs; "
    "95% bootstrap CIs in brackets."
)


def bold_note(a: Analysis) -> str:
    """What bold and italics mean in a table of this report, for the systems that ran.

    Bold marks the best model per column (:func:`povagent.report.tables.best_rows`), so it needs
    two models; with one, or with baselines only, the caption says that nothing is bolded
    rather than promising a best model that is not there.
    """
    models = a.model_systems
    refs = [s.system for s in a.systems if s.reference]
    if len(models) >= 2:
        text = "The best model per column is in bold."
    elif models:
        text = "One model ran: nothing is bolded."
    else:
        text = "Only baselines ran, no model: nothing is bolded (bold marks the best model)."
    if refs:
        where = " below the models, for reference, never bolded" if models else ", for reference"
        text += f" Baselines are in italics{where}: {', '.join(refs)}."
    return text


def row_header(a: Analysis) -> str:
    """The header of a table's row labels: what a row is."""
    return "Model · strategy" if a.model_systems else "Baseline"


def scored_systems(a: Analysis, protocol: str) -> list[SystemStats]:
    """The systems with rows under ``protocol``: a protocol's tables leave out a system whose
    answers are no point (a multiple-choice run has its own tables, :mod:`povagent.report.choice_tables`)."""
    under = {o.system for o in a.observations if o.protocol == protocol}
    return [s for s in a.systems if s.system in under]


def main_table(a: Analysis) -> Table:
    """Systems x conditions, official mean L2."""
    t = Table("main", "Main results", f"{PROTOCOL} {bold_note(a)}", row_header(a), [Column(condition_label(c)) for c in a.conditions])
    for s in scored_systems(a, "normalized_l2"):
        t.rows.append(Row(s.system, [_cell(_pick(s.by_condition, c, cell_error)) for c in a.conditions], s.reference))
    return t


def _strategy_varies(a: Analysis) -> bool:
    return len({s.axes.get("strategy", "") for s in a.model_systems}) > 1


def ablation_table(a: Analysis) -> Table | None:
    """Strategy x condition with the response rate, when the sweep varies the strategy."""
    if not _strategy_varies(a):
        return None
    models = {s.axes.get("model", "") for s in a.model_systems}
    one_model = len(models) == 1
    cols = [Column(condition_label(c)) for c in a.conditions] + [Column("Resp.", "rate", "higher")]
    caption = f"{PROTOCOL} Resp. is the response rate (answered / total) over all conditions. {bold_note(a)}"
    title = "Ablation" + (f" ({next(iter(models))})" if one_model and next(iter(models)) else "")
    t = Table("ablation", title, caption, row_header(a), cols)
    for s in scored_systems(a, "normalized_l2"):
        label = s.system  # model and strategy, as in every table (the title alone is easy to miss)
        cells = [_cell(_pick(s.by_condition, c, cell_error)) for c in a.conditions]
        cells.append(_cell(s.overall.response_rate))
        t.rows.append(Row(label, cells, s.reference))
    return t


def direction_table(a: Analysis) -> Table:
    """Systems x directions (pooled over conditions), official mean L2."""
    t = Table(
        "per_direction",
        "Error by direction",
        f"{PROTOCOL} Pooled over conditions. {bold_note(a)}",
        row_header(a),
        [Column(d.capitalize()) for d in a.directions],
    )
    for s in scored_systems(a, "normalized_l2"):
        t.rows.append(Row(s.system, [_cell(_pick(s.by_direction, d, cell_error)) for d in a.directions], s.reference))
    return t


def condition_direction_table(a: Analysis) -> Table:
    """Systems x (condition, direction), official mean L2 (no CIs: the table is wide)."""
    keys = [(c, d) for c in a.conditions for d in a.directions]
    cols = [Column(f"{condition_label(c)[0]}-{d}") for c, d in keys]
    t = Table(
        "per_condition_direction",
        "Error by condition and direction",
        f"Mean normalized L2 over answered instances (I = Inferred, S = Stated, G = Given); CIs in the CSV. {bold_note(a)}",
        row_header(a),
        cols,
        show_ci=False,
    )
    for s in scored_systems(a, "normalized_l2"):
        t.rows.append(Row(s.system, [_cell(_pick(s.by_condition_direction, f"{c}/{d}", cell_error)) for c, d in keys], s.reference))
    return t


def response_table(a: Analysis) -> Table:
    """Systems x conditions, response rate, plus all conditions."""
    cols = [Column(condition_label(c), "rate", "higher") for c in a.conditions] + [Column("Overall", "rate", "higher")]
    # a response as the protocol scorer counts it, else as the rows' status says
    what = "a parseable coordinate" if a.has_official or a.has_success else "a row whose status is answered"
    caption = (
        f"Answered / total instances (a response is {what}; unparseable answers and "
        "API failures are non-responses), averaged over runs; 95% bootstrap CIs. Overall pools "
        "every instance, which equals the paper's average over conditions when, as in POVBench, "
        "each condition has the same instances. " + bold_note(a)
    )
    t = Table("response_rates", "Response rates", caption, row_header(a), cols)
    for s in a.systems:
        cells = [_cell(_pick(s.by_condition, c, cell_response)) for c in a.conditions]
        cells.append(_cell(s.overall.response_rate))
        t.rows.append(Row(s.system, cells, s.reference))
    return t


def metric_variants_table(a: Analysis) -> Table:
    """Per system and condition: official beside counting non-responses, strict, frame selection."""
    cols = [
        Column("Official", "l2", None),
        Column("Counting non-resp.", "l2", None),
        Column("Strict", "l2", None),
        Column("GT in selected frame", "rate", None),
        Column("GT behind camera", "rate", None),
        Column("Resp.", "rate", None),
    ]
    caption = (
        "Official: mean L2 over answered instances (the benchmark's number, unchanged). "
        "Counting non-resp.: an unanswered instance scores as the center guess. "
        "Strict: a GT behind the selected frame's camera or outside the frame counts as a miss "
        "(sqrt 2 = 1.414) instead of being placed at the image centre. GT in selected frame: "
        "share of answered instances whose GT projects inside the scored frame (for Inferred/"
        "Stated, the frame-selection accuracy). GT behind camera: share scored by the blind spot. "
        "Rows mix conditions, so nothing is bolded."
    )
    t = Table("metric_variants", "Official metric and its variants", caption, row_header(a) + " / condition", cols)
    for s in a.systems:
        for c in a.conditions:
            cs = s.by_condition.get(c)
            if cs is None:
                continue
            t.rows.append(
                Row(
                    f"{s.system} / {condition_label(c)}",
                    [_cell(cs.official), _cell(cs.counted), _cell(cs.strict), _cell(cs.in_frame), _cell(cs.behind), _cell(cs.response_rate)],
                    s.reference,
                )
            )
    return t


SUCCESS_PROTOCOL = (
    "Success rate (higher is better): hits / all instances, an unanswered instance counting as a "
    "failure (the paper's protocol for real houses); a hit is an answer within a marked point's "
    "radius or inside a marked box or region. Averaged over runs; 95% bootstrap CIs in brackets."
)


def success_table(a: Analysis) -> Table:
    """Systems x conditions (and all conditions), success rate, with the response rate."""
    several = len(a.conditions) > 1
    overall = "Overall" if several or not a.conditions else condition_label(a.conditions[0])
    cols = [Column(condition_label(c), "rate", "higher") for c in a.conditions] if several else []
    cols += [Column(overall, "rate", "higher"), Column("Resp.", "rate", "higher")]
    caption = SUCCESS_PROTOCOL + (" Overall pools every instance." if several else "") + " Resp. is the response rate (answered / total). " + bold_note(a)
    t = Table("success", "Success rate", caption, row_header(a), cols)
    for s in scored_systems(a, "marked_hit"):
        cells = [_cell(_pick(s.by_condition, c, cell_hit)) for c in a.conditions] if several else []
        cells += [_cell(s.overall.success), _cell(s.overall.response_rate)]
        t.rows.append(Row(s.system, cells, s.reference))
    return t


def success_direction_table(a: Analysis) -> Table:
    """Systems x directions (pooled over conditions), success rate."""
    t = Table(
        "success_by_direction",
        "Success rate by direction",
        f"{SUCCESS_PROTOCOL} Pooled over conditions. {bold_note(a)}",
        row_header(a),
        [Column(d.capitalize(), "rate", "higher") for d in a.directions],
    )
    for s in scored_systems(a, "marked_hit"):
        t.rows.append(Row(s.system, [_cell(_pick(s.by_direction, d, cell_hit)) for d in a.directions], s.reference))
    return t


def paired_table(a: Analysis) -> Table | None:
    """Paired comparisons: B - A on shared instances with CI and tests."""
    if not a.comparisons:
        return None
    cols = [
        Column("n", "count", None),
        Column("Mean A", "l2", None),
        Column("Mean B", "l2", None),
        Column("B - A", "signed", None),
        Column("B better", "count", None),
        Column("A better", "count", None),
        Column("Wilcoxon p", "p", None),
        Column("Sign p", "p", None),
    ]
    caption = (
        "Paired comparison on the instances both systems answered (per-instance errors averaged "
        "over runs). B - A < 0 means B is better; 95% bootstrap CI of the mean difference; "
        "two-sided Wilcoxon signed-rank and exact sign tests (ties dropped). 'counted' scores "
        "non-responses as the center guess. 'success' compares per-instance hit rates over every "
        "instance (unanswered = miss): there B - A > 0 means B is better."
    )
    t = Table("paired", "Paired comparisons", caption, "B vs A (metric)", cols)
    for c in a.comparisons:
        t.rows.append(
            Row(
                f"{c.b} vs {c.a} ({c.metric})",
                [
                    Cell(c.n_pairs),
                    Cell(c.mean_a),
                    Cell(c.mean_b),
                    Cell(c.diff.value, c.diff.lo, c.diff.hi),
                    Cell(c.b_better),
                    Cell(c.a_better),
                    Cell(c.wilcoxon_p),
                    Cell(c.sign_p),
                ],
            )
        )
    return t


def paper_tables(a: Analysis) -> list[Table]:
    """Every table of a report, in reading order: the official tables for a POVBench-format
    set, the success tables for a real-world set (both when a collection mixes them), then a
    table per other scorer's declared metrics."""
    tables: list[Table | None] = []
    if a.has_official:
        tables += [main_table(a), ablation_table(a), direction_table(a), condition_direction_table(a)]
    if a.has_success:
        tables += [success_table(a), success_direction_table(a)]
    tables.append(response_table(a))
    if a.has_official:
        tables.append(metric_variants_table(a))
    tables.append(paired_table(a))
    tables += declared_metric_tables(a)  # every other scorer's declared metrics
    return [t for t in tables if t is not None]


#: The slices a declared metric's table shows as columns, beside ``Overall``.
_SLICE_WORDS = {"per_condition": ("condition", condition_label), "per_direction": ("direction", str.capitalize)}


def declared_metric_tables(a: Analysis) -> list[Table]:
    """A table per declared metric that no protocol's table shows (every metric of a scorer
    following no protocol, a protocol scorer's others: :meth:`Analysis.metrics_of_own`): a
    row per system, a column per condition and ``Overall`` (and a second table by direction,
    when several), each cell the metric's value with its declared bootstrap CI, bold on the
    better side the metric declares."""
    tables: list[Table] = []
    for scorer in a.declared:
        by_system = a.declared_estimates.get(scorer, {})
        for m in a.metrics_of_own(scorer).values():
            for slice_key, (word, label) in _SLICE_WORDS.items():
                keys = list(a.conditions if slice_key == "per_condition" else a.directions)
                if slice_key == "per_direction" and len(keys) < 2:
                    continue
                tables.append(_declared_metric_table(a, scorer, m, by_system, slice_key, word, [(k, label(k)) for k in keys]))
    return tables


def _declared_metric_table(a: Analysis, scorer: str, m: Any, by_system: dict[str, Any], slice_key: str, word: str, keys: list[tuple[str, str]]) -> Table:
    """One declared metric per system: a column per slice of ``slice_key``, then overall."""
    kind: Kind = "rate" if m.aggregation == "rate" else "l2"
    columns = [Column(text, kind, m.better) for _, text in keys] + [Column("Overall", kind, m.better)]
    safe = re.sub(r"[^A-Za-z0-9_]+", "_", f"{scorer}_{m.name}")
    key = f"metric_{safe}" + ("" if slice_key == "per_condition" else "_by_direction")
    better = "higher" if m.better == "higher" else "lower"
    caption = (
        f"{m.caption} Scorer {scorer}; {better} is better; per {word} and overall, pooling every run's rows; 95% bootstrap CIs in brackets. {bold_note(a)}"
    )
    title = f"{m.label} ({scorer})" + ("" if slice_key == "per_condition" else " by direction")
    t = Table(key, title, caption, row_header(a), columns)
    for s in a.systems:
        cells = by_system.get(s.system)
        if cells is None:
            continue
        per = cells[slice_key]
        row = [_cell(per[k][m.name]) if k in per else Cell(None) for k, _ in keys] + [_cell(cells["overall"][m.name])]
        t.rows.append(Row(s.system, row, s.reference))
    return t

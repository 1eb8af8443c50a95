"""The report's figures, drawn from an analysis: error by condition, by direction, by
condition x direction, predicted vs GT scatter, and the error distribution (rows of a
``normalized_l2`` scorer); for a real-world set (a ``marked_hit`` scorer), success rate by
condition and by direction; for every other scorer, each declared metric by condition.

Chooses what to plot; :mod:`povagent.report.plots` draws it. Returns SVG strings by name;
writing them is the caller's job.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Callable

from povagent.report.analysis import Analysis
from povagent.report.paper_tables import cell_error, cell_hit, condition_label
from povagent.report.statistics import CellStats, Estimate

#: Scatter plots are drawn for at most this many systems (the first ones).
MAX_SCATTER_SYSTEMS = 6
#: Declared metrics are plotted for at most this many (the first declared); every one has its table.
MAX_METRIC_PLOTS = 12


def _safe_name(text: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in text).strip("_").lower()[:60] or "system"


def _of(cell: CellStats | None, number: Callable[[CellStats], Estimate]) -> Estimate | None:
    return number(cell) if cell is not None else None


def _baseline_note(a: Analysis, drawn_as: str) -> str:
    """How the plot sets baselines apart, when it has any (``drawn_as``: "hatched bars")."""
    refs = [s.system for s in a.systems if s.reference]
    return f" Baselines ({', '.join(refs)}): {drawn_as} and hollow markers." if refs else ""


def report_figures(a: Analysis, frame_size: Callable[[str], tuple[int, int]] | None = None) -> dict[str, tuple[str, str]]:
    """Figures by file stem: ``(caption, svg)``. ``frame_size(instance_id)`` gives (W, H) for
    the scatter's pixel-to-fraction conversion (512 x 512 when unknown)."""
    figs: dict[str, tuple[str, str]] = {}
    if a.has_official:
        figs |= _official_figures(a, frame_size)
    if a.has_success:
        figs |= _success_figures(a)
    figs |= declared_metric_figures(a)
    return figs


def declared_metric_figures(a: Analysis) -> dict[str, tuple[str, str]]:
    """A plot per declared metric that no protocol's figure shows (:meth:`Analysis.metrics_of_own`):
    the metric per condition and overall, a bar per system with its declared bootstrap CI."""
    from povagent.report.plots import grouped_bars

    figs: dict[str, tuple[str, str]] = {}
    for scorer in a.declared:
        by_system = a.declared_estimates.get(scorer, {})
        for m in a.metrics_of_own(scorer).values():
            if len(figs) >= MAX_METRIC_PLOTS:
                return figs
            series = [
                (
                    s.system,
                    [*(by_system[s.system]["per_condition"].get(c, {}).get(m.name) for c in a.conditions), by_system[s.system]["overall"][m.name]],
                    s.reference,
                )
                for s in a.systems
                if s.system in by_system
            ]
            better = "higher" if m.better == "higher" else "lower"
            # only the groupings the rows have: a set without conditions is plotted overall
            grouped = " by condition" if a.conditions else ""
            figs[f"metric_{_safe_name(scorer)}_{_safe_name(m.name)}"] = (
                f"{m.label} ({scorer}){grouped and grouped + ' and'} overall; {better} is better (whiskers: 95% bootstrap CI)."
                + _baseline_note(a, "hatched bars"),
                grouped_bars(
                    f"{m.label}{grouped}",
                    [*(condition_label(c) for c in a.conditions), "Overall"],
                    series,
                    y_label=m.label.lower(),
                    y_limit=1.0 if m.aggregation == "rate" else None,
                ),
            )
    return figs


def _success_figures(a: Analysis) -> dict[str, tuple[str, str]]:
    from povagent.report.plots import grouped_bars

    figs: dict[str, tuple[str, str]] = {}
    series = [(s.system, [_of(s.by_condition.get(c), cell_hit) for c in a.conditions], s.reference) for s in a.systems]
    figs["success_by_condition"] = (
        "Success rate by condition (unanswered = failure; whiskers: 95% bootstrap CI)." + _baseline_note(a, "hatched bars"),
        grouped_bars("Success rate by condition", [condition_label(c) for c in a.conditions], series, y_label="success rate", y_limit=1.0),
    )
    series = [(s.system, [_of(s.by_direction.get(d), cell_hit) for d in a.directions], s.reference) for s in a.systems]
    figs["success_by_direction"] = (
        "Success rate by direction, pooled over conditions." + _baseline_note(a, "hatched bars"),
        grouped_bars("Success rate by direction", [d.capitalize() for d in a.directions], series, y_label="success rate", y_limit=1.0),
    )
    return figs


def _official_figures(a: Analysis, frame_size: Callable[[str], tuple[int, int]] | None) -> dict[str, tuple[str, str]]:
    from povagent.report.plots import grouped_bars, histogram, scatter

    size = frame_size or (lambda _id: (512, 512))
    figs: dict[str, tuple[str, str]] = {}
    series = [(s.system, [_of(s.by_condition.get(c), cell_error) for c in a.conditions], s.reference) for s in a.systems]
    figs["error_by_condition"] = (
        "Mean normalized L2 by condition (answered instances; whiskers: 95% bootstrap CI)." + _baseline_note(a, "hatched bars"),
        grouped_bars("Error by condition", [condition_label(c) for c in a.conditions], series),
    )
    series = [(s.system, [_of(s.by_direction.get(d), cell_error) for d in a.directions], s.reference) for s in a.systems]
    figs["error_by_direction"] = (
        "Mean normalized L2 by direction, pooled over conditions." + _baseline_note(a, "hatched bars"),
        grouped_bars("Error by direction", [d.capitalize() for d in a.directions], series),
    )
    keys = [(c, d) for c in a.conditions for d in a.directions]
    series = [(s.system, [_of(s.by_condition_direction.get(f"{c}/{d}"), cell_error) for c, d in keys], s.reference) for s in a.systems]
    figs["error_by_condition_direction"] = (
        "Mean normalized L2 by condition (I, S, G) and direction." + _baseline_note(a, "hatched bars"),
        grouped_bars("Error by condition x direction", [f"{condition_label(c)[0]}-{d}" for c, d in keys], series, width=max(820, 70 * len(keys))),
    )
    by_sys: dict[str, list] = defaultdict(list)
    for o in a.observations:
        if o.answered and o.gt_u is not None and o.gt_v is not None and o.x is not None and o.y is not None:
            by_sys[o.system].append(o)
    cond_index = {c: i for i, c in enumerate(a.conditions)}
    names = [condition_label(c) for c in a.conditions]
    for s in [s for s in a.systems if not s.reference][:MAX_SCATTER_SYSTEMS]:
        pts_x, pts_y = [], []
        for o in by_sys.get(s.system, []):
            w, h = size(o.instance_id)
            k = cond_index.get(o.condition, 0)
            pts_x.append((o.gt_u, o.x / w, k))
            pts_y.append((o.gt_v, o.y / h, k))
        stem = _safe_name(s.system)
        figs[f"scatter_x_{stem}"] = (
            f"{s.system}: predicted vs GT x (fractions of the frame; the dashed line is a perfect answer).",
            scatter(f"{s.system}: x", pts_x, names, "GT x / W", "predicted x / W"),
        )
        figs[f"scatter_y_{stem}"] = (
            f"{s.system}: predicted vs GT y.",
            scatter(f"{s.system}: y", pts_y, names, "GT y / H", "predicted y / H"),
        )
    hist = [(s.system, [o.l2 for o in by_sys.get(s.system, []) if o.l2 is not None], s.reference) for s in a.systems]
    figs["error_distribution"] = (
        "Distribution of the normalized L2 of answered instances (share per bin; all runs)." + _baseline_note(a, "dashed lines"),
        histogram("Error distribution", hist),
    )
    return figs

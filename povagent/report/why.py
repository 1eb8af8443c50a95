"""The report's "Why it fails" section: failure steps, egocentric bias, relation-consistent success.

An addition, labelled as one (docs/how-to/why-models-fail.md): shown only when the runs were scored with
``diagnose`` and/or ``relation`` (``scorers: [official, diagnose, relation]``, or ``povagent
rescore RUN --scorer diagnose --scorer relation`` and a report of the rescored folder). From
each system's ``diagnostics`` breakdown (:func:`~povagent.report.analysis.system_diagnostics`):

* a stacked bar per system and condition of the first failing step (each part a link to those
  answers in the gallery);
* a table of the steps over all conditions, each share a link to the gallery filtered to that
  system and step ("every viewpoint failure of a model");
* the egocentric-bias index with its 95% CI and the answers it counts (Inferred, Stated; Given
  has none: the observer view is the camera);
* relation-consistent success beside the official mean L2 of the same rows, per direction.

Markup only: the numbers come from the analysis, the gallery does the filtering.
"""

from __future__ import annotations

import html
from typing import Any
from urllib.parse import quote

from povagent.report.analysis import Analysis, SystemStats
from povagent.report.paper_tables import condition_label
from povagent.report.plots import StackedBar, stacked_bars
from povagent.scoring.diagnosis import STEPS

#: A colour per step (Okabe-Ito): failures warm to cool in the order they are tested, success green.
STEP_COLOURS = {"frame": "#D55E00", "anchor": "#E69F00", "viewpoint": "#CC79A7", "placement": "#56B4E9", "correct": "#009E73"}
#: The figure's file stem (``plots/<stem>.svg``).
FIGURE = "failure_steps"


def gallery_link(system: str, **state: str) -> str:
    """The address of a gallery state: ``#system=<name>&cond=a&step=viewpoint`` (the system
    written as the page writes it: ``/`` between its axis values)."""
    parts = [f"system={quote(system.replace(' · ', '/'), safe='')}"] + [f"{k}={quote(v, safe='')}" for k, v in state.items()]
    return "#" + "&".join(parts)


def _diagnosed(a: Analysis) -> list[SystemStats]:
    return [s for s in a.systems if s.diagnostics is not None]


def _conditions(s: SystemStats) -> list[tuple[str, dict[str, Any]]]:
    cells = (s.diagnostics or {}).get("per_condition") or {}
    return [(c, cells[c]) for c in ("a", "b", "c") if c in cells] + sorted((c, v) for c, v in cells.items() if c not in ("a", "b", "c"))


def failure_steps_figure(a: Analysis) -> tuple[str, str] | None:
    """``(caption, svg)`` of the stacked bars, or ``None`` when no row was diagnosed."""
    bars = [
        StackedBar(s.system, condition_label(c), dict(cell["failure_steps"]), {step: gallery_link(s.system, cond=c, step=step) for step in STEPS})
        for s in _diagnosed(a)
        for c, cell in _conditions(s)
        if cell.get("n_diagnosed")
    ]
    if not bars:
        return None
    caption = (
        "Addition, not in the paper: the first failing step of each answered row, per system and condition (share of "
        "diagnosed rows, all runs). Click a part for those answers in the gallery (each system's first run)."
    )
    return caption, stacked_bars("Why answers fail: first failing step", bars, list(STEPS), [STEP_COLOURS[s] for s in STEPS])


def _pct(value: float | None) -> str:
    return "--" if value is None else f"{100 * value:.1f}%"


def _steps_table(systems: list[SystemStats]) -> str:
    head = "".join(f"<th>{html.escape(step)}</th>" for step in STEPS)
    rows = []
    for s in systems:
        counts = {step: 0.0 for step in STEPS}
        n = 0
        for _, cell in _conditions(s):
            k = cell.get("n_diagnosed") or 0
            n += k
            for step in STEPS:
                counts[step] += (cell["failure_steps"].get(step) or 0.0) * k
        cells = "".join(
            f'<td><a href="{html.escape(gallery_link(s.system, step=step))}" data-step="{step}">{_pct(counts[step] / n if n else None)}</a></td>'
            for step in STEPS
        )
        rows.append(f'<tr data-system="{html.escape(s.system)}"><th scope="row">{html.escape(s.system)}</th>{cells}<td>{n}</td></tr>')
    return (
        '<div class="table-box"><table class="results" id="table-failure_steps"><caption>First failing step over every condition '
        "(share of diagnosed rows, all runs). Each share links to those answers in the gallery, which shows each system's "
        "first run.</caption>"
        f'<thead><tr><th scope="col">System</th>{head}<th>rows</th></tr></thead><tbody>{"".join(rows)}</tbody></table></div>'
    )


def _bias_table(systems: list[SystemStats]) -> str:
    conds = [c for c in ("a", "b") if any(c in ((s.diagnostics or {}).get("per_condition") or {}) for s in systems)]
    head = "".join(f"<th>{html.escape(condition_label(c))}</th>" for c in conds)
    rows = []
    for s in systems:
        cells = []
        for c in conds:
            cell = ((s.diagnostics or {}).get("per_condition") or {}).get(c) or {}
            value, ci, n = cell.get("egocentric_bias"), cell.get("egocentric_bias_ci"), cell.get("bias_n", 0)
            text = "--" if value is None else f"{value:.2f}"
            if ci:
                text += f' <span class="ci">[{ci[0]:.2f}, {ci[1]:.2f}]</span>'
            cells.append(f'<td data-cond="{c}">{text} <span class="ci">n {n}</span></td>')
        rows.append(f'<tr data-system="{html.escape(s.system)}"><th scope="row">{html.escape(s.system)}</th>{"".join(cells)}</tr>')
    return (
        '<div class="table-box"><table class="results" id="table-egocentric_bias"><caption>Egocentric-bias index: among answers '
        "that found the frame and the anchor, where the egocentric and the observer-relative targets lie more than 0.05 apart "
        "(n of them), the share nearer the egocentric one; 95% bootstrap CI over instances. 0: follows the observer; 1: "
        "follows the camera. Given has none: the observer view is the camera.</caption>"
        f'<thead><tr><th scope="col">System</th>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table></div>'
    )


def _relation_table(systems: list[SystemStats], directions: list[str]) -> str:
    head = "".join(f"<th>{html.escape(d)}</th>" for d in directions)
    rows = []
    for s in systems:
        for c, cell in _conditions(s):
            per = cell.get("per_direction") or {}
            tds = []
            for d in directions:
                here = per.get(d) or {}
                l2 = here.get("official_mean_l2")
                tds.append(f'<td data-dir="{d}">{_pct(here.get("relation_success"))} <span class="ci">L2 {"--" if l2 is None else f"{l2:.3f}"}</span></td>')
            label = f"{s.system} · {condition_label(c)}"
            rows.append(
                f'<tr data-system="{html.escape(s.system)}" data-cond="{c}"><th scope="row">{html.escape(label)}</th>'
                f"<td>{_pct(cell.get('relation_success'))}</td>{''.join(tds)}</tr>"
            )
    return (
        '<div class="table-box"><table class="results" id="table-relation"><caption>Relation-consistent success: the share '
        "of answered rows whose point lands where a valid 0.4 m target could stand, beside the official mean L2 of the same "
        "rows, per direction (all runs).</caption>"
        f'<thead><tr><th scope="col">System · condition</th><th>all</th>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table></div>'
    )


def why_section(a: Analysis, figure: tuple[str, str] | None) -> str:
    """The section's markup (empty when no row carries a ``diagnose`` or ``relation`` score)."""
    systems = _diagnosed(a)
    if not systems:
        return ""
    parts = [
        '<section id="why"><h2>Why it fails <span class="muted">(addition, not in the paper)</span></h2>',
        '<p class="help">From the <code>diagnose</code> and <code>relation</code> scores of the rows (docs/how-to/why-models-fail.md). '
        "The gallery filters by failure step (<code>step=viewpoint</code> in its address) and draws the egocentric and "
        "mirrored targets beside the ground truth when asked (<code>cf=1</code>).</p>",
    ]
    if figure is not None:
        caption, svg = figure
        parts.append(f'<figure id="fig-{FIGURE}">{svg}<figcaption>{html.escape(caption)}</figcaption></figure>')
    if any(any(cell.get("n_diagnosed") for _, cell in _conditions(s)) for s in systems):
        parts.append(_steps_table(systems))
        parts.append(_bias_table(systems))
    parts.append(_relation_table(systems, a.directions))
    parts.append("</section>")
    return "".join(parts)

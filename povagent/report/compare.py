"""Comparing two runs instance by instance (``povagent compare RUN_A RUN_B``).

For each instance both runs evaluated: each run's official error averaged over its run indices
(answered only), the difference B - A, and whether the answer status changed. The summary
gives, overall and per condition, the paired comparison (mean difference with a bootstrap CI,
Wilcoxon and sign tests); the instances that changed most come first (the largest |B - A|, then
the instances answered by only one run).

Computes and renders; the CLI prints the terminal view and writes the HTML.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from povagent.errors import PredictionsError
from povagent.report.collect import Collection, Observation, collect
from povagent.report.statistics import DEFAULT_BOOT, PairedComparison, paired_comparison
from povagent.results.summary_json import summary_json_text


@dataclass(frozen=True)
class InstanceDelta:
    """One instance in both runs (errors averaged over run indices; ``None``: never answered)."""

    instance_id: str
    condition: str
    direction: str
    a: float | None
    b: float | None

    @property
    def delta(self) -> float | None:
        """B - A when both answered."""
        return None if self.a is None or self.b is None else self.b - self.a

    @property
    def change(self) -> str:
        """``both``, ``only_a`` (B stopped answering), ``only_b`` (B newly answers) or ``neither``."""
        if self.a is not None and self.b is not None:
            return "both"
        if self.a is not None:
            return "only_a"
        return "only_b" if self.b is not None else "neither"


@dataclass
class RunComparison:
    """Two runs compared."""

    a_name: str
    b_name: str
    a_obs: list[Observation]
    b_obs: list[Observation]
    deltas: list[InstanceDelta]
    overall: PairedComparison
    per_condition: dict[str, PairedComparison]

    def most_changed(self, n: int = 20) -> list[InstanceDelta]:
        """The ``n`` instances that changed most: largest |B - A|, then answer-status changes."""
        scored = sorted((d for d in self.deltas if d.delta is not None), key=lambda d: -abs(d.delta or 0.0))
        flipped = [d for d in self.deltas if d.change in ("only_a", "only_b")]
        return (scored + flipped)[:n] if n else scored + flipped

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {
            "a": self.a_name,
            "b": self.b_name,
            "overall": self.overall.as_dict(),
            "per_condition": {k: v.as_dict() for k, v in self.per_condition.items()},
            "instances": [
                {"instance_id": d.instance_id, "a": d.a, "b": d.b, "delta": d.delta, "change": d.change} for d in self.deltas
            ],
        }


def _mean_answered(obs: list[Observation]) -> dict[str, float]:
    acc: dict[str, list[float]] = defaultdict(list)
    for o in obs:
        if o.answered and o.l2 is not None:
            acc[o.instance_id].append(o.l2)
    return {k: sum(v) / len(v) for k, v in acc.items()}


def _relabel(collection: Collection, label: str) -> list[Observation]:
    from dataclasses import replace

    return [replace(o, system=label) for o in collection.observations]


def run_label(path: Path, collection: Collection) -> str:
    """A short name for a run: its folder name and its system."""
    system = collection.systems[0] if collection.systems else ""
    return f"{path.name} ({system})" if system and system != path.name else path.name


def compare_runs(run_a: str | Path, run_b: str | Path, n_boot: int = DEFAULT_BOOT, seed: int = 0) -> RunComparison:
    """Compare two run folders on the instances they share."""
    pa, pb = Path(run_a), Path(run_b)
    ca, cb = collect(pa), collect(pb)
    for path, c in ((pa, ca), (pb, cb)):
        if len(c.systems) > 1:
            # averaging one instance over different models would compare nothing real
            raise PredictionsError(
                f"{path}: holds {len(c.systems)} systems ({', '.join(c.systems[:4])}); compare two run folders "
                f"(e.g. {path}/<cell>), or a sweep whose cells differ only by run or condition"
            )
    na, nb = run_label(pa, ca), run_label(pb, cb)
    if na == nb:
        na, nb = f"A: {na}", f"B: {nb}"
    a_obs, b_obs = _relabel(ca, na), _relabel(cb, nb)
    ma, mb = _mean_answered(a_obs), _mean_answered(b_obs)
    meta: dict[str, tuple[str, str]] = {o.instance_id: (o.condition, o.direction) for o in a_obs}
    shared = sorted(set(meta) & {o.instance_id for o in b_obs})
    deltas = [InstanceDelta(i, meta[i][0], meta[i][1], ma.get(i), mb.get(i)) for i in shared]
    keep = set(shared)
    a_obs = [o for o in a_obs if o.instance_id in keep]
    b_obs = [o for o in b_obs if o.instance_id in keep]
    overall = paired_comparison(na, a_obs, nb, b_obs, n_boot=n_boot, seed=seed)
    per_c: dict[str, PairedComparison] = {}
    for cond in sorted({d.condition for d in deltas}):
        per_c[cond] = paired_comparison(
            na, [o for o in a_obs if o.condition == cond], nb, [o for o in b_obs if o.condition == cond], n_boot=n_boot, seed=seed
        )
    return RunComparison(na, nb, a_obs, b_obs, deltas, overall, per_c)


def _f(v: float | None, signed: bool = False) -> str:
    if v is None or not math.isfinite(v):
        return "--"
    return f"{v:+.3f}" if signed else f"{v:.3f}"


def _p(v: float | None) -> str:
    return "--" if v is None else ("<0.001" if v < 0.001 else f"{v:.3f}")


def print_comparison(cmp: RunComparison, top: int = 15, console: Any = None) -> None:
    """The comparison in the terminal: summary per condition, then the most-changed instances."""
    from rich import box
    from rich.console import Console
    from rich.table import Table

    from povagent.report.paper_tables import condition_label

    console = console or Console()
    t = Table(
        title=f"B = {cmp.b_name} vs A = {cmp.a_name}\nofficial L2 on instances both answered; B-A < 0 and B:A = B better:A better",
        box=box.SIMPLE_HEAD,
        padding=(0, 1),
        collapse_padding=True,
        pad_edge=False,
    )
    for col in ("subset", "n", "A", "B", "B-A", "95% CI", "B:A", "Wilcoxon", "sign"):
        t.add_column(col, justify="left" if col == "subset" else "right", no_wrap=True)
    rows = [("all", cmp.overall)] + [(condition_label(c), p) for c, p in cmp.per_condition.items()]
    for name, p in rows:
        ci = f"[{_f(p.diff.lo, True)}, {_f(p.diff.hi, True)}]"
        t.add_row(name, str(p.n_pairs), _f(p.mean_a), _f(p.mean_b), _f(p.diff.value, True), ci, f"{p.b_better}:{p.a_better}", _p(p.wilcoxon_p), _p(p.sign_p))
    console.print(t)
    only_a = sum(1 for d in cmp.deltas if d.change == "only_a")
    only_b = sum(1 for d in cmp.deltas if d.change == "only_b")
    console.print(f"{len(cmp.deltas)} shared instances; answered only by A: {only_a}; only by B: {only_b}")
    m = Table(title=f"Instances that changed most (top {top})", box=box.SIMPLE_HEAD, pad_edge=False)
    for col in ("instance", "A", "B", "B - A", "change"):
        m.add_column(col, justify="left" if col in ("instance", "change") else "right")
    for d in cmp.most_changed(top):
        m.add_row(d.instance_id, _f(d.a), _f(d.b), _f(d.delta, True), d.change)
    console.print(m)


def write_comparison_html(cmp: RunComparison, out: str | Path, dataset: Any = None, top: int | None = None) -> Path:
    """``out/compare.html``: the summary table and a gallery of A's and B's drawings side by
    side, sorted by |B - A| (filterable like the report's gallery)."""

    from povagent.report.gallery import ANSWERS_DIR, build_gallery, write_answer_chunks
    from povagent.report.html import OFFICIAL_LEGEND, render_page
    from povagent.report.paper_tables import condition_label
    from povagent.report.tables import Cell, Column, Row, Table, to_html

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    ea, a_stats = build_gallery(cmp.a_obs, [cmp.a_name], dataset, out)
    eb, _ = build_gallery(cmp.b_obs, [cmp.b_name], dataset, out)
    by_b = {e["id"]: e for e in eb}
    deltas = {d.instance_id: d for d in cmp.deltas}
    # repeats per side: the cards' headline is the mean over them (what the delta compares)
    n_repeats = max(len({o.run for o in cmp.a_obs}), len({o.run for o in cmp.b_obs}), 1)
    entries = []
    for e in ea:
        b = by_b.get(e["id"])
        if b is None:
            continue
        d = deltas.get(e["id"])
        entries.append(
            e
            | {
                "s": 0,
                "img_b": b["img"],
                "ie_b": b.get("ie"),
                "e_b": b["e"],
                "a_b": b["a"],
                "tr_b": b.get("tr"),
                "nt_b": b.get("nt"),
                "ps_b": b["ps"],
                "k_b": b["k"],
                "ma": None if d is None or d.a is None else round(d.a, 4),
                "mb": None if d is None or d.b is None else round(d.b, 4),
                "nr": n_repeats,
                "dl": None if d is None or d.delta is None else round(d.delta, 4),
            }
        )
    entries.sort(key=lambda e: -abs(e["dl"]) if e["dl"] is not None else 0.0)
    if top:
        entries = entries[:top]
    answers = write_answer_chunks(entries, out, keys=("a", "a_b", "tr", "tr_b"))
    cols = [Column("n", "count", None), Column("Mean A", "l2", None), Column("Mean B", "l2", None), Column("B - A", "signed", None),
            Column("B better", "count", None), Column("A better", "count", None), Column("Wilcoxon p", "p", None), Column("Sign p", "p", None)]
    table = Table(
        "compare",
        "Paired comparison",
        f"A = {cmp.a_name}; B = {cmp.b_name}. Official L2 on instances both answered (averaged over runs); B - A < 0 means B is better; 95% bootstrap CI.",
        "Subset",
        cols,
    )
    for name, p in [("All", cmp.overall)] + [(condition_label(c), p) for c, p in cmp.per_condition.items()]:
        table.rows.append(
            Row(
                name,
                [
                    Cell(p.n_pairs),
                    Cell(p.mean_a),
                    Cell(p.mean_b),
                    Cell(p.diff.value, p.diff.lo, p.diff.hi),
                    Cell(p.b_better),
                    Cell(p.a_better),
                    Cell(p.wilcoxon_p),
                    Cell(p.sign_p),
                ],
            )
        )
    body = '<section id="tables"><h2>Summary</h2>' + to_html(table) + "</section>"
    page = render_page(
        f"povagent compare: {cmp.b_name} vs {cmp.a_name}",
        f"{len(cmp.deltas)} shared instances; cards show A (left) and B (right), sorted by |B - A| "
        "(errors averaged over each run's repeats; drawings of the first repeat)",
        body,
        {
            "systems": [f"{cmp.a_name} | {cmp.b_name}"],
            "entries": entries,
            "images_dir": "images",
            "answers_dir": ANSWERS_DIR,
            "answers": answers,
            "default_sort": "delta-desc",
            # both runs show the same houses and targets: A's strips serve B's pick too
            "strips": a_stats.strips,
            "views": a_stats.views,
        },
        nav=[("#tables", "Summary")],
        legend=OFFICIAL_LEGEND + " In the strip, <span style=\"color:#2d7dff;font-weight:700\">blue outline</span>: the frame B selected (red: A's).",
        sort_extra='<option value="delta-desc">|B - A|, largest first</option>',
    )
    from povagent.files.confined_write import write_inside

    # aside and renamed: a link planted at either name is replaced, never followed
    path = write_inside(out, "compare.html", page)
    write_inside(out, "compare.json", summary_json_text(cmp.as_dict()))
    return path

"""The report's "Active" section (an addition, not in the paper): looking around vs not.

What it is for: when a report's runs include the ``active`` strategy (rows whose final answer
is an episode record, :mod:`povagent.results.episode`), this section sets each active system
beside every passive system on the same instances: official L2 per condition with the paired
difference and its bootstrap CI, the actions the episodes used, L2 against the action budget,
and for a few episodes the trajectory seen from above (frames, path, headings, the view answered
in, the target) with the views it rendered (read from the run folder's ``views/``). What it
must not do: score (the rows' scores are read as they are) or render anything of a house.
"""

from __future__ import annotations

import dataclasses
import html
import math
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from PIL import Image

from povagent.active.views import view_file
from povagent.dataset.instances import Frame
from povagent.generate.floorplan import FloorPlan
from povagent.report.collect import Collection, Observation
from povagent.report.floor_plan import floor_plan_svg, house_plan, plan_points
from povagent.report.statistics import paired_comparison
from povagent.report.step_caption import ELLIPSIS, step_caption
from povagent.results.episode import EpisodeRecord, read_record
from povagent.scoring.bootstrap import bootstrap_mean_ci
from povagent.scoring.normalized_l2 import answered_in_camera

#: Episodes drawn per active system, views and steps shown per episode, and the thumbnail side (px).
TRAJECTORIES_PER_SYSTEM = 6
VIEWS_PER_EPISODE = 10
STEPS_PER_EPISODE = 12
THUMB_PX = 128
CONDITION_LABELS = {"a": "Inferred (A)", "b": "Stated (B)", "c": "Given (C)"}


@dataclass(frozen=True)
class AnsweredView:
    """What the gallery draws for an active row: the image answered in when it is a rendered
    view (its camera, and its PNG in the run folder; ``None`` for an exploration frame, drawn as
    usual), the episode's poses (x, z, yaw), start first, for the bird's-eye card, and every view
    the episode rendered (their PNGs, view 1 first) with the number of the one answered in."""

    frame: Frame | None
    path: tuple[tuple[float, float, float], ...]
    views: tuple[Path, ...] = ()
    answered: int | None = None


def answered_view(observation: Observation, folders: Mapping[str, Path]) -> AnsweredView | None:
    """The gallery's view of an active row (``None`` for a passive row)."""
    record = read_record(observation.raw)
    if record is None:
        return None
    path = tuple((c.x, c.z, c.yaw) for c in [record.start, *(v.camera for v in record.views)])
    files = [view_file(folders.get(observation.run_name, Path()), v.sha256) for v in record.views]
    if any(f is None for f in files):  # missing, or planted (a link, a pipe): the card draws no view
        return AnsweredView(None, path)
    views = tuple(f for f in files if f is not None)
    answer = record.answer
    if answer is None or answer.frame is not None:
        return AnsweredView(None, path, views)
    number = int(answer.image.split()[1])
    if not 1 <= number <= len(record.views):
        return AnsweredView(None, path, views)
    return AnsweredView(dataclasses.replace(answered_in_camera(answer.camera), file=views[number - 1]), path, views, number)


@dataclass(frozen=True)
class Episode:
    """One active row as the section reads it: its observation, record and run folder."""

    observation: Observation
    record: EpisodeRecord
    folder: Path


def active_episodes(collection: Collection) -> dict[str, list[Episode]]:
    """Episodes by active system, in the collection's order (empty: no active run)."""
    folders = {r.name: r.folder for r in collection.runs}
    out: dict[str, list[Episode]] = defaultdict(list)
    for o in collection.observations:
        record = read_record(o.raw)
        if record is not None:
            out[o.system].append(Episode(o, record, folders.get(o.run_name, Path())))
    return dict(out)


def _fmt(v: float | None, signed: bool = False) -> str:
    if v is None or not math.isfinite(v):
        return "--"
    return f"{v:+.3f}" if signed else f"{v:.3f}"


def _ci(lo: float | None, hi: float | None) -> str:
    return "" if lo is None or hi is None else f" [{lo:+.3f}, {hi:+.3f}]"


def comparison_rows(collection: Collection, episodes: dict[str, list[Episode]], n_boot: int, seed: int) -> list[dict[str, Any]]:
    """Active vs each passive system, per condition and overall: paired official L2."""
    by_system: dict[str, list[Observation]] = defaultdict(list)
    for o in collection.observations:
        by_system[o.system].append(o)
    passive = [s for s in collection.systems if s not in episodes and by_system.get(s)]
    rows = []
    for active in episodes:
        for other in passive:
            for cond in ["all", *sorted({o.condition for o in by_system[active]})]:
                pick = (lambda o: True) if cond == "all" else (lambda o, c=cond: o.condition == c)
                c = paired_comparison(
                    other, [o for o in by_system[other] if pick(o)], active, [o for o in by_system[active] if pick(o)], n_boot=n_boot, seed=seed
                )
                if c.n_pairs:
                    rows.append({"active": active, "passive": other, "condition": cond, **c.as_dict()})
    return rows


def usage_rows(episodes: dict[str, list[Episode]]) -> list[dict[str, Any]]:
    """Per active system: the distribution of actions used and the mean of each count."""
    rows = []
    for system, eps in episodes.items():
        counts = [e.record.counts for e in eps]
        n = len(counts)
        rows.append(
            {
                "system": system,
                "episodes": n,
                "actions": dict(sorted(Counter(c.actions for c in counts).items())),
                **{f"mean_{k}": sum(getattr(c, k) for c in counts) / n for k in ("actions", "views", "questions", "blocked_moves", "invalid_calls")},
                "answered_in_text": sum(1 for e in eps if e.record.answer is not None and e.record.answer.via == "text"),
                "no_answer": sum(1 for e in eps if e.record.answer is None),
            }
        )
    return rows


def budget_rows(episodes: dict[str, list[Episode]], n_boot: int, seed: int) -> list[dict[str, Any]]:
    """Per active system and action budget: official L2 with its CI (answered rows)."""
    rows = []
    for system, eps in episodes.items():
        by_budget: dict[int, list[float]] = defaultdict(list)
        for e in eps:
            if e.observation.answered and e.observation.l2 is not None:
                by_budget[e.record.budget].append(e.observation.l2)
        for budget, values in sorted(by_budget.items()):
            est = bootstrap_mean_ci(values, n_boot=n_boot, seed=seed)
            rows.append({"system": system, "budget": budget, **est.as_dict()})
    return rows


def trajectory_svg(record: EpisodeRecord, target: tuple[float, float, float] | None, px: int = 280, plan: FloorPlan | None = None) -> str:
    """The episode from above: the house's floor plan (rooms and walls, when ``plan`` is given:
    the map then spans the whole house), the path, a heading at each view, the view answered
    in (red wedge), the target (green). x to the right, z up the page."""
    pts = [(c.x, c.z) for c in [record.start, *[v.camera for v in record.views]]]
    if target is not None:
        pts.append((target[0], target[2]))
    margin = 1.0
    if plan is not None:
        pts += plan_points(plan)
        margin = 0.3
    x0, x1 = min(p[0] for p in pts) - margin, max(p[0] for p in pts) + margin
    z0, z1 = min(p[1] for p in pts) - margin, max(p[1] for p in pts) + margin
    scale = px / max(x1 - x0, z1 - z0)

    def at(x: float, z: float) -> tuple[float, float]:
        return round((x - x0) * scale, 1), round(px - (z - z0) * scale, 1)

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{px}" height="{px}" viewBox="0 0 {px} {px}">',
        f'<rect width="{px}" height="{px}" fill="#fafafa" stroke="#ccc"/>',
    ]
    if plan is not None:
        parts.append(floor_plan_svg(plan, at))
    path = " ".join(f"{a},{b}" for a, b in (at(c.x, c.z) for c in [record.start, *[v.camera for v in record.views]]))
    parts.append(f'<polyline points="{path}" fill="none" stroke="#2962ff" stroke-width="1.5"/>')
    answered = record.answer.camera if record.answer is not None else None
    for v in record.views:
        a, b = at(v.camera.x, v.camera.z)
        yaw = math.radians(v.camera.yaw)
        tip = (a + 12 * math.sin(yaw), b - 12 * math.cos(yaw))
        parts.append(f'<line x1="{a}" y1="{b}" x2="{tip[0]:.1f}" y2="{tip[1]:.1f}" stroke="#2962ff"/><text x="{a + 3}" y="{b - 3}" font-size="9">{v.n}</text>')
    if answered is not None:
        a, b = at(answered.x, answered.z)
        half = math.radians(answered.fov / 2)
        yaw = math.radians(answered.yaw)
        wedge = [(a, b)] + [(a + 40 * math.sin(yaw + s * half), b - 40 * math.cos(yaw + s * half)) for s in (-1, 1)]
        parts.append('<polygon points="' + " ".join(f"{p:.1f},{q:.1f}" for p, q in wedge) + '" fill="#ff2d2d33" stroke="#ff2d2d"/>')
    if target is not None:
        a, b = at(target[0], target[2])
        parts.append(f'<circle cx="{a}" cy="{b}" r="4" fill="#00c853"/>')
    a, b = at(record.start.x, record.start.z)
    parts.append(f'<rect x="{a - 3}" y="{b - 3}" width="6" height="6" fill="#616161"/></svg>')
    return "".join(parts)


def _thumbnail(folder: Path, sha: str, out: Path) -> str | None:
    """A JPEG thumbnail of a rendered view under ``out/images/active`` (``None``: not on disk)."""
    target = out / "images" / "active" / f"{sha}.jpg"
    if not target.is_file():
        source = view_file(folder, sha)
        if source is None:
            return None
        target.parent.mkdir(parents=True, exist_ok=True)
        with Image.open(source) as im:
            im.convert("RGB").resize((THUMB_PX, THUMB_PX)).save(target, format="JPEG", quality=80)
    return f"images/active/{sha}.jpg"


def _episode_card(e: Episode, dataset: Any, out: Path) -> str:
    inst = dataset.instance(e.observation.instance_id) if dataset is not None else None
    plan = house_plan(getattr(dataset, "root", None), e.observation.house_id)
    svg = trajectory_svg(e.record, tuple(inst.target) if inst is not None else None, plan=plan)
    answered = e.record.answer.image if e.record.answer is not None else "no answer"
    views = []
    for v in e.record.views[:VIEWS_PER_EPISODE]:
        src = _thumbnail(e.folder, v.sha256, out)
        mark = ' class="answered"' if answered == f"view {v.n}" else ""
        views.append(
            f'<figure{mark}><img src="{src}" alt="View {v.n}"><figcaption>View {v.n}</figcaption></figure>'
            if src
            else f"<figure><figcaption>View {v.n} (not in the run folder)</figcaption></figure>"
        )
    steps = ", ".join(html.escape(step_caption(s.action, s.arguments)) for s in e.record.steps[:STEPS_PER_EPISODE])
    if len(e.record.steps) > STEPS_PER_EPISODE:
        steps += html.escape(f", {ELLIPSIS} ({len(e.record.steps) - STEPS_PER_EPISODE} more steps)")
    l2 = _fmt(e.observation.l2)
    return (
        f'<div class="active-episode"><h4>{html.escape(e.observation.instance_id)} · answered in {html.escape(answered)} · L2 {l2}</h4>'
        f'{svg}<div class="views">{"".join(views)}</div><p class="muted">{steps}</p></div>'
    )


def active_section(collection: Collection, dataset: Any, out: Path, n_boot: int = 2000, seed: int = 0) -> tuple[str, dict[str, Any]]:
    """The section's markup and its numbers (``("", {})`` when no run is active)."""
    episodes = active_episodes(collection)
    if not episodes:
        return "", {}
    comparisons = comparison_rows(collection, episodes, n_boot, seed)
    usage = usage_rows(episodes)
    budgets = budget_rows(episodes, n_boot, seed)
    parts = [
        '<section id="active"><h2>Active <span class="muted">(addition, not in the paper)</span></h2>',
        '<p class="help">The <code>active</code> strategy lets a model look around the house with tool calls before it '
        "answers (docs/how-to/active.md). Official L2 in the camera of the image answered in; each active system beside "
        "each passive system on the same instances (difference active - passive, 95% bootstrap CI; negative: looking helped). "
        "In Inferred (A), <code>ask</code> answers with the Stated sentence (where the speaker was) unless the strategy "
        "ran with <code>speaker: condition</code>, which keeps the speaker to what the condition gives (in A: what they "
        "were doing, not where): with the default, A and B nearly meet once a model asks.</p>",
        "<table><tr><th>active</th><th>passive</th><th>condition</th><th>pairs</th><th>L2 passive</th><th>L2 active</th>"
        "<th>difference [CI]</th><th>active better</th></tr>",
    ]
    for r in comparisons:
        d = r["mean_diff_b_minus_a"]
        parts.append(
            f"<tr><td>{html.escape(r['active'])}</td><td>{html.escape(r['passive'])}</td>"
            f"<td>{CONDITION_LABELS.get(r['condition'], 'all')}</td><td>{r['n_pairs']}</td><td>{_fmt(r['mean_a'])}</td>"
            f"<td>{_fmt(r['mean_b'])}</td><td>{_fmt(d['value'], True)}{_ci(d['ci_lo'], d['ci_hi'])}</td>"
            f"<td>{r['b_better']} of {r['n_pairs']}</td></tr>"
        )
    if not comparisons:
        parts.append('<tr><td colspan="8">no passive run of the same instances in this report</td></tr>')
    parts.append(
        "</table><h3>Actions used</h3><table><tr><th>system</th><th>episodes</th><th>actions: episodes</th><th>mean actions</th>"
        "<th>views</th><th>questions</th><th>blocked moves</th><th>invalid calls</th><th>answered in text</th><th>no answer</th></tr>"
    )
    for u in usage:
        dist = ", ".join(f"{k}: {v}" for k, v in u["actions"].items())
        parts.append(
            f"<tr><td>{html.escape(u['system'])}</td><td>{u['episodes']}</td><td>{dist}</td><td>{u['mean_actions']:.2f}</td>"
            f"<td>{u['mean_views']:.2f}</td><td>{u['mean_questions']:.2f}</td><td>{u['mean_blocked_moves']:.2f}</td>"
            f"<td>{u['mean_invalid_calls']:.2f}</td><td>{u['answered_in_text']}</td><td>{u['no_answer']}</td></tr>"
        )
    parts.append("</table><h3>L2 against the action budget</h3><table><tr><th>system</th><th>budget</th><th>answered</th><th>L2 [CI]</th></tr>")
    for b in budgets:
        parts.append(
            f"<tr><td>{html.escape(b['system'])}</td><td>{b['budget']}</td><td>{b['n']}</td><td>{_fmt(b['value'])}{_ci(b['ci_lo'], b['ci_hi'])}</td></tr>"
        )
    parts.append("</table><h3>Trajectories</h3>")
    for system, eps in episodes.items():
        parts.append(f"<h4>{html.escape(system)}</h4>")
        parts += [_episode_card(e, dataset, out) for e in eps[:TRAJECTORIES_PER_SYSTEM]]
    parts.append("</section>")
    return "".join(parts), {"comparisons": comparisons, "actions": usage, "budgets": budgets}

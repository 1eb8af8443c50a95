"""The numbers of a report: per system, overall and broken down by condition and direction.

Takes a :class:`~povagent.report.collect.Collection` (and, when it can be loaded, the dataset
the runs used) and computes every statistic the tables, plots and JSON summary show: official
means with CIs, response rates, the strict and counting-non-responses variants, frame-selection
accuracy, the computed center baseline, and paired comparisons between systems. Runs on a
real-world set (scored by a ``marked_hit`` scorer) get success rates instead, with the same
machinery. Every scorer's declared metrics are estimated per system and slice
(:func:`declared_metric_estimates`), whatever the scorer: a run scored only by a third party's
scorer gets those and its response rate, never an error table it did not ask for.

It never changes a run's number: those come from the rows' stored scores.
"""

from __future__ import annotations

import hashlib
import math
from collections import Counter, defaultdict
from dataclasses import dataclass, field, replace
from itertools import combinations
from pathlib import Path
from typing import Any

import numpy as np

from povagent.dataset.release_models import CONDITIONS, DIRECTIONS
from povagent.report.baseline import (
    CENTER_POLICY,
    CENTER_SUCCESS_POLICY,
    CENTER_SYSTEM,
    center_observations,
    center_score,
    center_success_observations,
)
from povagent.report.baseline_systems import is_baseline_system, is_center_system
from povagent.report.collect import Collection, Observation
from povagent.report.declared_metrics import declared_estimates_json, declared_metric_estimates
from povagent.report.statistics import DEFAULT_BOOT, CellStats, Compared, PairedComparison, cell_stats, paired_comparison
from povagent.report.systems import config_label
from povagent.scoring.breakdown import POOLED, ScoredRow, pooled_breakdown, slices
from povagent.scoring.metrics import Metric
from povagent.scoring.score_protocols import PROTOCOLS

#: Above this many systems, paired comparisons are against the first system only.
MAX_ALL_PAIRS = 6


@dataclass
class SystemStats:
    """One system's numbers."""

    system: str
    axes: dict[str, str]
    reference: bool
    overall: CellStats
    by_condition: dict[str, CellStats]
    by_direction: dict[str, CellStats]
    by_condition_direction: dict[str, CellStats]
    #: The official numbers with every run's rows in one mean (not the paper's aggregation, which
    #: the cells above follow): ``{}`` for a system without official scores.
    pooled: dict[str, Any] = field(default_factory=dict)
    #: The ``diagnostics`` breakdown of the rows' ``diagnose`` and ``relation`` scores (an
    #: addition, :func:`~povagent.scoring.diagnostics_breakdown.diagnostics_breakdown`); ``None``
    #: when no row carries them.
    diagnostics: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {
            "system": self.system,
            "axes": self.axes,
            "reference": self.reference,
            "overall": self.overall.as_dict(),
            "per_condition": {k: v.as_dict() for k, v in self.by_condition.items()},
            "per_direction": {k: v.as_dict() for k, v in self.by_direction.items()},
            "per_condition_direction": {k: v.as_dict() for k, v in self.by_condition_direction.items()},
            "pooled": self.pooled,
            "diagnostics": self.diagnostics,
        }


def pooled_official(observations: list[Observation]) -> dict[str, Any]:
    """A system's official numbers pooled over runs (every row in one mean), labelled ``pooled``.

    The report's cells are means of per-run means, as the paper reports several runs; the
    pooled numbers are kept beside them for comparison only. Non-finite means become ``None``
    (the report's JSON is strict).
    """
    rows = [
        ScoredRow(o.condition, o.direction, o.answered and o.l2 is not None, o.l2, o.gt_in_frame, o.l2_strict, o.run)
        for o in observations
        if o.protocol == "normalized_l2"
    ]
    if not rows:
        return {}
    b = pooled_breakdown(rows)

    def cell(c: dict[str, Any]) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in c.items()}

    return {
        "aggregation": POOLED,
        "overall": cell(b["overall"]),
        "per_condition": {k: cell(v) for k, v in b["per_condition"].items()},
        "per_direction": {k: cell(v) for k, v in b["per_direction"].items()},
    }


@dataclass
class Analysis:
    """Everything computed for one report."""

    source: Path
    systems: list[SystemStats]
    comparisons: list[PairedComparison]
    observations: list[Observation]
    conditions: list[str]
    directions: list[str]
    center_fill: dict[str, float] | None
    dataset_path: Path | None
    notes: list[str] = field(default_factory=list)
    #: The scorers whose protocol fields the rows carry, in :data:`PROTOCOLS` order (one per protocol).
    scorers: list[str] = field(default_factory=list)
    #: Their protocols, in the same order.
    protocols: list[str] = field(default_factory=list)
    #: Every scorer's declared metrics (:mod:`povagent.scoring.metrics`), as the runs' summaries
    #: record them, and per scorer and system each metric's estimate over the system's rows, per
    #: slice (``{"overall": {metric: estimate}, "per_condition": {c: ...}, "per_direction": ...}``).
    declared: dict[str, dict[str, Metric]] = field(default_factory=dict)
    declared_estimates: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)

    @property
    def has_official(self) -> bool:
        """True when some rows carry POVBench's normalized L2 (a scorer following ``normalized_l2``)."""
        return "normalized_l2" in self.protocols

    @property
    def has_success(self) -> bool:
        """True when some rows carry hits against hand-marked ground truth (``marked_hit``)."""
        return "marked_hit" in self.protocols

    def scorer_of(self, protocol: str) -> str | None:
        """The scorer whose rows follow ``protocol`` (``None``: no row does)."""
        return next((s for s, p in zip(self.scorers, self.protocols) if p == protocol), None)

    def metrics_of_own(self, scorer: str) -> dict[str, Metric]:
        """``scorer``'s declared metrics that get tables and plots of their own: all of them, but
        those its protocol's tables show already (:func:`~povagent.scoring.score_protocols.beyond_protocol`);
        none when no row was estimated."""
        from povagent.scoring.score_protocols import beyond_protocol

        if scorer not in self.declared_estimates:
            return {}
        return beyond_protocol(self.declared.get(scorer, {}), dict(zip(self.scorers, self.protocols)).get(scorer))

    def system(self, name: str) -> SystemStats:
        """The stats of one system by label."""
        for s in self.systems:
            if s.system == name:
                return s
        raise KeyError(name)

    @property
    def has_diagnostics(self) -> bool:
        """True when some system's rows carry ``diagnose`` or ``relation`` scores."""
        return any(s.diagnostics is not None for s in self.systems)

    @property
    def model_systems(self) -> list[SystemStats]:
        """Systems that are not a reference baseline."""
        return [s for s in self.systems if not s.reference]

    def as_dict(self) -> dict[str, Any]:
        """JSON-able summary of the whole analysis (observations excluded)."""
        return {
            "source": str(self.source),
            "dataset": str(self.dataset_path) if self.dataset_path else None,
            "scorers": self.scorers,
            "conditions": self.conditions,
            "directions": self.directions,
            "systems": [s.as_dict() for s in self.systems],
            "metrics": declared_estimates_json(self.declared_estimates),
            "paired_comparisons": [c.as_dict() for c in self.comparisons],
            "notes": self.notes,
        }


#: How a count of each identity axis reads (singular, plural).
_AXIS_WORDS = {"model": ("model", "models"), "strategy": ("strategy", "strategies"), "parser": ("parser", "parsers")}


def _count(n: int, axis: str) -> str:
    one, many = _AXIS_WORDS.get(axis, (f"{axis} value", f"{axis} values"))
    return f"{n} {one if n == 1 else many}"


def what_was_compared(a: Analysis) -> str:
    """The report's header line on what ran: ``1 model x 5 strategies · 1 baseline: center``.

    The models are counted along the axes their labels are made of (model, strategy, then any
    other axis that varies among them); a full grid reads as a product, anything else as its
    system count with the distinct values per axis. Baselines are counted and named apart.
    """
    models = a.model_systems
    parts: list[str] = []
    if models:
        axes = ["model", "strategy"] + sorted(
            {k for s in models for k in s.axes if k not in ("model", "strategy", "backend")
             and len({m.axes.get(k, "") for m in models}) > 1}
        )
        counts = {k: len({s.axes.get(k, "") for s in models}) for k in axes if any(s.axes.get(k) for s in models)}
        product = 1
        for n in counts.values():
            product *= n
        grid = " x ".join(_count(n, k) for k, n in counts.items())
        parts.append(grid if product == len(models) else f"{len(models)} systems ({grid.replace(' x ', ', ')})")
    refs = [s.system for s in a.systems if s.reference]
    if refs:
        parts.append(f"{len(refs)} baseline{'s' if len(refs) > 1 else ''}: {', '.join(refs)}")
    return " · ".join(parts) or "no system"


def _answers_signature(obs: list[Observation]) -> str:
    """A digest of what a system answered, row by row, in any order (equal digests: the same
    answers). The declared metrics' values are in it: answers that are no pixel (a navigate
    walk) differ by what they scored. Each row is digested on its own (128-bit BLAKE2b) and the
    row digests are sorted, so nothing a row is held but 16 bytes."""
    digests = bytearray()
    for o in obs:
        row = (
            o.instance_id,
            o.run,
            o.answered,
            None if o.l2 is None else round(o.l2, 12),
            o.success,
            o.selected_image,
            o.x,
            o.y,
            sorted((scorer, sorted(values.items())) for scorer, values in o.metric_values.items()),
        )
        digests += hashlib.blake2b(repr(row).encode(), digest_size=16).digest()
    pairs = np.frombuffer(bytes(digests), dtype=">u8").reshape(-1, 2)
    return hashlib.sha256(pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))].tobytes()).hexdigest()


def merge_identical_baselines(
    ordered: list[str], by_system: dict[str, list[Observation]], axes_of: dict[str, dict[str, str]], reference: set[str],
    labelled: frozenset[str] = frozenset(),
) -> tuple[list[str], list[str]]:
    """Show a baseline once when a sweep crossed it with axes it ignores.

    A sweep over ``backend: [model, center]`` x ``strategy: [basic, cot]`` makes ``center ·
    basic`` and ``center · cot``: the center guess ignores the prompt, so the two cells hold the
    same answers. Reference systems of one backend and model with identical answers on every row
    are merged into one, labelled by the axis values they share (``center``). Updates
    ``by_system``, ``axes_of`` and ``reference`` in place; returns the new system order and a
    note per merge. Models are never merged: two strategies that happen to agree are still two
    rows of an ablation; nor are two different baselines that happen to agree (the ``oracle``
    and an always-``A`` guess on a set whose gold is always A), nor a system its run's config
    names (``labelled``: the user asked for that row).
    """
    candidates = [name for name in ordered if name in reference and name not in labelled]
    backend_model = {name: (axes_of[name].get("backend", ""), axes_of[name].get("model", "")) for name in candidates}
    shared_by = Counter(backend_model.values())
    groups: dict[tuple[str, str, str | None], list[str]] = {}
    for name in candidates:
        # only a baseline sharing its backend and model with another can be merged: the others'
        # answers are never digested (a pass over every row of theirs)
        signature = _answers_signature(by_system[name]) if shared_by[backend_model[name]] > 1 else None
        groups.setdefault((*backend_model[name], signature), []).append(name)
    notes: list[str] = []
    rename: dict[str, str] = {}
    shared_axes: dict[str, dict[str, str]] = {}
    used = set(by_system)
    for names in groups.values():
        if len(names) < 2:
            continue
        shared = {k: v for k, v in axes_of[names[0]].items() if all(axes_of[n].get(k) == v for n in names[1:])}
        label = shared.get("model") or shared.get("backend") or names[0]
        if label in used and label not in names:
            label = names[0]
        used.add(label)
        rename[names[0]] = label
        shared_axes[label] = shared
        for n in names[1:]:
            rename[n] = ""
        notes.append(f"{', '.join(names)} answered identically on every row: shown once as '{label}'.")
    if not rename:
        return ordered, notes
    out: list[str] = []
    for name in ordered:
        new = rename.get(name, name)
        if not new:
            by_system.pop(name, None)
            continue
        if new != name:
            by_system[new] = [replace(o, system=new) for o in by_system.pop(name)]
            axes_of[new] = shared_axes[new]
            reference.add(new)
        out.append(new)
    return out, notes


def system_diagnostics(observations: list[Observation], n_boot: int, seed: int) -> dict[str, Any] | None:
    """The ``diagnostics`` breakdown of one system's rows, from their stored ``diagnose`` and
    ``relation`` scores, through the one function ``summary.json`` uses (``None``: none carry them)."""
    from povagent.scoring.diagnostics_breakdown import DiagnosedRow, diagnostics_breakdown

    rows = [
        DiagnosedRow(o.instance_id, o.condition, o.direction, o.l2, o.fail_step, o.nearer_egocentric, o.relation)
        for o in observations
        if o.fail_step is not None or o.relation is not None
    ]
    return diagnostics_breakdown(rows, n_boot=n_boot, seed=seed)


def _stats_for(obs: list[Observation], fill, n_boot: int, seed: int, conditions, directions) -> tuple:
    """``(overall, per condition, per direction, per condition x direction)`` cells of one
    system, through the one breakdown (:func:`povagent.scoring.breakdown.slices`), kept to the
    report's conditions and directions."""
    b = slices(obs, lambda sub: cell_stats(sub, fill, n_boot, seed))
    per_cd = {f"{c}/{d}": b["per_condition_direction"][f"{c}/{d}"] for c in conditions for d in directions if f"{c}/{d}" in b["per_condition_direction"]}
    return (
        b["overall"],
        {c: b["per_condition"][c] for c in conditions if c in b["per_condition"]},
        {d: b["per_direction"][d] for d in directions if d in b["per_direction"]},
        per_cd,
    )


def analyze(
    collection: Collection,
    dataset: Any = None,
    dataset_note: str | None = None,
    n_boot: int = DEFAULT_BOOT,
    seed: int = 0,
) -> Analysis:
    """Compute every number of a report (``dataset`` enables the center baseline and the
    counting-non-responses variant; without it they are left out with a note)."""
    notes: list[str] = []
    obs = list(collection.observations)
    # an external multiple-choice item has no condition or direction (its rows write ""): no column
    present_c = {o.condition for o in obs if o.condition}
    present_d = {o.direction for o in obs if o.direction}
    conditions = [str(c) for c in CONDITIONS if str(c) in present_c] + sorted(present_c - {str(c) for c in CONDITIONS})
    directions = [str(d) for d in DIRECTIONS if str(d) in present_d] + sorted(present_d - {str(d) for d in DIRECTIONS})

    systems = collection.systems
    center_cells = [s for s in systems if is_center_system(collection.system_axes(s), s)]
    protocols: list[str] = [p for p in PROTOCOLS if any(o.protocol == p for o in obs)]
    scorers = [next(o.scorer for o in obs if o.protocol == p) for p in protocols]
    error_scorer = scorers[protocols.index("normalized_l2")] if "normalized_l2" in protocols else None
    hit_scorer = scorers[protocols.index("marked_hit")] if "marked_hit" in protocols else None
    fill: dict[str, float] | None = None
    if dataset is not None and (error_scorer or hit_scorer):
        # the center guess is a point: only for the rows a point protocol scored (a choice run beside has none)
        ids = sorted({o.instance_id for o in obs if o.protocol in ("normalized_l2", "marked_hit")})
        instances = [dataset.instance(i) for i in ids]
        missing = [i for i, inst in zip(ids, instances) if inst is None]
        instances = [inst for inst in instances if inst is not None]
        if missing:
            notes.append(f"{len(missing)} instance(s) of the runs are not in the dataset (e.g. {missing[0]}): no center score for them")
        if _is_realworld(dataset):
            # hand-marked 2D ground truth: no official score, so no center fill either
            if not center_cells and hit_scorer is not None:
                scorer, options_note = _hit_scorer(collection, hit_scorer)
                obs = obs + center_success_observations(instances, scorer, hit_scorer)
                notes.append(f"'{CENTER_SYSTEM}' is computed by the report (no center cell in the sweep): it {CENTER_SUCCESS_POLICY}{options_note}.")
        elif error_scorer is not None:
            fill = {}
            for inst in instances:
                s = center_score(inst)
                if s.l2 is not None:
                    fill[inst.id] = s.l2
            if not center_cells:
                obs = obs + center_observations(instances, error_scorer)
                notes.append(f"'{CENTER_SYSTEM}' is computed by the report (no center cell in the sweep): it {CENTER_POLICY}.")
            notes.append(
                "'Counting non-responses' scores an unanswered instance as the center guess "
                "(same policy as the center baseline) instead of dropping it."
            )
    elif error_scorer or hit_scorer:
        notes.append(
            "Center baseline and the counting-non-responses variant need the dataset: "
            + (dataset_note or "not available")
            + "."
        )

    by_system: dict[str, list[Observation]] = defaultdict(list)
    for o in obs:
        by_system[o.system].append(o)
    ordered = [s for s in systems if s in by_system] + [s for s in by_system if s not in systems]
    axes_of = {name: dict(collection.system_axes(name)) for name in ordered}
    reference_set = {n for n in ordered if n == CENTER_SYSTEM or is_baseline_system(axes_of[n], n)}
    labelled = frozenset(r.system for r in collection.runs if config_label(r.config))
    ordered, merge_notes = merge_identical_baselines(ordered, by_system, axes_of, reference_set, labelled)
    notes.extend(merge_notes)
    obs = [o for name in ordered for o in by_system[name]]
    stats: list[SystemStats] = []
    for name in ordered:
        overall, per_c, per_d, per_cd = _stats_for(by_system[name], fill, n_boot, seed, conditions, directions)
        stats.append(
            SystemStats(name, axes_of[name], name in reference_set, overall, per_c, per_d, per_cd, pooled_official(by_system[name]),
                        system_diagnostics(by_system[name], n_boot, seed))
        )

    comparisons: list[PairedComparison] = []
    models = [s.system for s in stats if not s.reference]
    refs = [s.system for s in stats if s.reference]
    pairs = list(combinations(models, 2)) if len(models) <= MAX_ALL_PAIRS else [(models[0], m) for m in models[1:]]
    # what to compare, and the name a comparison shows: the protocol scorer's, or "counted"
    compared: list[tuple[Compared, str]] = []
    if error_scorer is not None:
        compared.append(("l2", error_scorer))
        if fill is not None:
            compared.append(("counted", "counted"))
    if hit_scorer is not None:
        compared.append(("hit", hit_scorer))
    for a, b in pairs:
        for metric, label in compared:
            comparisons.append(paired_comparison(a, by_system[a], b, by_system[b], metric, fill, n_boot, seed, label))
    # models against the center baseline (the computed one, or the sweep's center cell)
    centers = [s for s in refs if s == CENTER_SYSTEM or is_center_system(axes_of[s], s)]
    for ref in centers[:1]:
        for m in models:
            for metric, label in [x for x in compared if x[0] != "counted"]:
                comparisons.append(paired_comparison(ref, by_system[ref], m, by_system[m], metric, fill, n_boot, seed, label))
    if error_scorer is not None:
        notes.append(
            "Means are over answered instances (official), averaged over runs: the mean of per-run "
            "means, as the paper reports several runs; brackets are 95% percentile bootstrap CIs "
            "resampling instances. summary.json also gives each system's 'pooled' numbers (every "
            "run's rows in one mean), which are not the paper's aggregation."
        )
        notes.append(
            "Strict: a GT behind the selected frame's camera or outside it counts as a miss (sqrt 2); "
            "the official metric puts a behind-camera GT at the image centre."
        )
    if hit_scorer is not None:
        notes.append(
            "Success rate (real-world set, hand-marked ground truth): hits / all instances, an "
            "unanswered instance counting as a failure, as the paper scores real houses. A hit is an "
            "answer within a marked point's radius, or inside a marked box or region, in the frame "
            "the model selected (Inferred, Stated) or the observer view (Given), as the success "
            "scorer recorded it in results.jsonl. Averaged over runs; brackets are 95% percentile "
            "bootstrap CIs resampling instances. This set has no 3D ground truth, so no official "
            "error is reported for it."
        )
    declared, estimates = declared_metric_estimates(collection, by_system, ordered, n_boot, seed)
    return Analysis(
        source=collection.source,
        systems=stats,
        comparisons=comparisons,
        observations=obs,
        conditions=conditions,
        directions=directions,
        center_fill=fill,
        dataset_path=getattr(dataset, "root", None),
        notes=notes,
        scorers=scorers,
        protocols=protocols,
        declared=declared,
        declared_estimates=estimates,
    )


def _is_realworld(dataset: Any) -> bool:
    from povagent.dataset.realworld_set import RealWorldDataset

    return isinstance(dataset, RealWorldDataset)


def _hit_scorer(collection: Collection, name: str) -> tuple[Any, str]:
    """The ``marked_hit`` scorer ``name`` as the runs configured it (through the plugin host,
    like a run), and a note when the runs disagree on its options (the first run's are used)."""
    from povagent.plugins import build_plugin_host

    options: list[dict[str, Any]] = []
    for r in collection.runs:
        for spec in r.config.get("scorers") or []:
            if isinstance(spec, dict) and spec.get("name") == name:
                options.append(dict(spec.get("options") or {}))
            elif spec == name:
                options.append({})
    chosen = options[0] if options else {}
    note = ""
    if any(o != chosen for o in options[1:]):
        note = f" (the runs score with different {name} options; the baseline uses the first run's, {chosen})"
    elif chosen:
        note = f" (options {chosen})"
    return build_plugin_host(strict=False).scorer(name, chosen), note

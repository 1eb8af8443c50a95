"""Which system each collected run is: a system is a run, never a merge.

A report compares *systems*. Each run folder (each cell of a sweep) is one system, named by the
``label:`` its config gives, else by the identity axes that vary across the collected runs
(model, strategy, parser, ...). Two runs whose names would collide stay two systems: each name is
made unique with its folder's name, since two runs that look alike by their configs may be
anything but (two servers behind one served model name: a base checkpoint and a fine-tuned one).
The one exception is a sweep that splits one system's evaluation into cells by condition or run
index (axes the tables break down or average): cells of one sweep whose axes differ only there
are that one system.

Runs asked different sets are never one system: runs sharing a name on several sets are one
system per set, named with the set (``gpt-4o · viewspatial``), and each keeps the name without
it as its ``entrant`` (a leaderboard's row).

Runs are pooled into one system only when the user asks: with ``pool=True`` (``povagent report
--pool``) runs of the same name pool, and runs whose configs give the same explicit ``label:``
always pool (the label says they are one system). Every pooling is returned as a
:class:`Pooling`, which the report prints, so it never happens silently.

This module only names runs; it reads no file and computes no number.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from povagent.report.baseline_systems import is_baseline_system

#: Sweep axes that are not part of a system's identity: tables break these down or average them.
NON_SYSTEM_AXES = frozenset({"run", "runs", "condition", "conditions", "condition_set", "conditions_set", "seed"})

#: Axis order used to build a system label (the most telling first).
AXIS_ORDER = ("model", "backend", "strategy", "parser")

#: Joins a system's axis values in its label (``gpt-4o · s-cot``).
LABEL_JOIN = " · "


class NamedRun(Protocol):
    """What naming needs of a collected run (:class:`povagent.report.collect.RunInfo`)."""

    name: str
    axes: dict[str, str]
    system: str
    #: The system's name without its set (set with :attr:`system`).
    entrant: str
    #: The sweep folder whose index listed the run (``None``: a run folder of its own).
    sweep: Any
    #: The axis values the sweep's index gives the cell (``{}`` for a run of its own).
    cell_axes: dict[str, str]

    @property
    def folder(self) -> Any: ...

    @property
    def config(self) -> dict[str, Any]: ...

    @property
    def benchmark(self) -> str: ...


@dataclass(frozen=True)
class Pooling:
    """Runs the report pooled into one system, and why."""

    system: str
    runs: tuple[str, ...]
    #: ``"label"``: their configs give the same ``label:``; ``"asked"``: ``--pool``.
    reason: str

    def note(self) -> str:
        """One sentence for the report's notes and the console."""
        why = "their configs give the same label" if self.reason == "label" else "--pool was given"
        return f"Pooled {len(self.runs)} runs into the system '{self.system}' ({why}): {', '.join(self.runs)}."


def simulation_label(options: Any) -> str:
    """How reports name a ``simulated`` backend: ``simulation (sigma 10 px, wrong furniture 0.2)``,
    its noise options that are set, so a reader never mistakes it for a model."""
    opts = options if isinstance(options, dict) else {}
    names = (
        ("pixel_sigma", "sigma {} px"),
        ("miss_rate", "miss {}"),
        ("wrong_furniture_rate", "wrong furniture {}"),
        ("wrong_surface_rate", "wrong surface {}"),
    )
    parts = [text.format(opts[k]) for k, text in names if opts.get(k)]
    return "simulation (" + (", ".join(parts) or "no noise") + ")"


def planted_label(options: Any) -> str:
    """How reports name a ``planted`` backend: ``planted simulation (egocentric 0.4, sigma 5 px)``."""
    opts = options if isinstance(options, dict) else {}
    names = (("egocentric", "egocentric {}"), ("mirror", "mirror {}"), ("random_frame", "random frame {}"), ("pixel_sigma", "sigma {} px"))
    parts = [text.format(opts[k]) for k, text in names if opts.get(k)]
    return "planted simulation (" + (", ".join(parts) or "ground truth") + ")"


def set_name(config: dict[str, Any], path: Any) -> str:
    """The set a run was asked, by name: an external set's ``dataset.format`` (``viewspatial``),
    else its folder's name (``path``), with the ``task:`` when it is not the point task
    (``release · relation``); ``""`` when the config names no set."""
    ds = config.get("dataset")
    format = ds.get("format") if isinstance(ds, dict) else None
    name = str(format) if format else (getattr(path, "name", "") if path is not None else "")
    task = config.get("task")
    task_name = task.get("name") if isinstance(task, dict) else task
    return f"{name}{LABEL_JOIN}{task_name}" if name and task_name not in (None, "", "point") else name


def config_label(config: dict[str, Any]) -> str | None:
    """The ``label:`` a run's config gives its system, or ``None``."""
    value = config.get("label")
    return value.strip() if isinstance(value, str) and value.strip() else None


def _is_baseline_run(run: NamedRun) -> bool:
    return is_baseline_system(run.axes, run.axes.get("model") or run.axes.get("backend", ""))


def axis_labels(runs: Sequence[NamedRun]) -> list[str]:
    """Each run's name from its axes: the values of the identity axes that vary across ``runs``.

    A model's name always holds its model and its strategy (``qwen3-vl-8b · cot``), even when
    one of them is the same in every run: a reader of a strategy sweep's table, plot legend or
    gallery card should never have to guess which model the strategies ran on. Baselines ignore
    the prompt, so theirs hold only what varies (``center``, ``random``).
    """
    keys: dict[str, None] = {}
    for r in runs:
        for k in r.axes:
            if k not in NON_SYSTEM_AXES:
                keys.setdefault(k, None)
    varying = [k for k in keys if len({r.axes.get(k, "") for r in runs}) > 1]
    ordered = [k for k in AXIS_ORDER if k in varying] + [k for k in varying if k not in AXIS_ORDER]
    if "model" in ordered and "backend" in ordered:
        # the model already names the backend in almost every sweep; keep one unless both matter
        pairs = {(r.axes.get("model"), r.axes.get("backend")) for r in runs}
        if len(pairs) == len({p[0] for p in pairs}):
            ordered.remove("backend")
    labels = []
    for r in runs:
        named = ordered
        if not _is_baseline_run(r):
            always = [k for k in ("model", "strategy") if r.axes.get(k) and k not in ordered]
            named = [k for k in AXIS_ORDER if k in ordered or k in always] + [k for k in ordered if k not in AXIS_ORDER]
        if named:
            labels.append(LABEL_JOIN.join(r.axes.get(k, "?") for k in named))
        else:
            labels.append(r.axes.get("model") or r.axes.get("backend") or r.name)
    return labels


def evaluations(runs: Sequence[NamedRun]) -> list[tuple[Any, ...]]:
    """What makes runs one system's evaluation, for each run: the cells of one sweep that differ
    only in condition or run index share one; any other run (or a cell whose axes repeat
    another's exactly) has its own."""
    repeats: dict[tuple[Any, ...], int] = {}
    keys: list[tuple[Any, ...]] = []
    for run in runs:
        if run.sweep is None:
            keys.append(("run", str(run.folder)))
            continue
        whole = (str(run.sweep), tuple(sorted(run.cell_axes.items())))
        repeats[whole] = repeats.get(whole, -1) + 1
        system_axes = tuple(sorted((k, v) for k, v in run.cell_axes.items() if k not in NON_SYSTEM_AXES))
        keys.append(("sweep", str(run.sweep), system_axes, repeats[whole]))
    return keys


def _folder_names(folders: Sequence[Any]) -> list[str]:
    """The shortest trailing part of each folder path that tells the folders apart."""
    parts = [tuple(str(p) for p in getattr(f, "parts", ())) or (str(f),) for f in folders]
    for depth in range(1, max(len(p) for p in parts) + 1):
        names = ["/".join(p[-depth:]) for p in parts]
        if len(set(names)) == len(names):
            return names
    return [f"{'/'.join(p)} #{i + 1}" for i, p in enumerate(parts)]


def assign_systems(runs: Sequence[NamedRun], *, pool: bool = False) -> list[Pooling]:
    """Set each run's ``system``; return the poolings made (empty unless asked or labelled).

    A run's name is its config's ``label:``, else :func:`axis_labels`. Runs sharing a name are
    pooled when they all give that same explicit label, or when ``pool`` is set; otherwise each
    evaluation (:func:`evaluations`: a run, or a sweep's cells split by condition or run) gets
    its folder's name appended (``openai/any · basic (base-run)``), so no two runs merge.
    """
    labels = axis_labels(runs)
    evaluation = evaluations(runs)
    explicit = [config_label(r.config) for r in runs]
    entrants = [e or a for e, a in zip(explicit, labels, strict=True)]
    # runs of one name asked different sets are one system per set: a set's number never pools another's
    sets_of: dict[str, set[str]] = {}
    for run, entrant in zip(runs, entrants, strict=True):
        sets_of.setdefault(entrant, set()).add(run.benchmark)
    names = [f"{e}{LABEL_JOIN}{r.benchmark}" if len(sets_of[e]) > 1 and r.benchmark else e for r, e in zip(runs, entrants, strict=True)]
    groups: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        groups.setdefault(name, []).append(i)
    poolings: list[Pooling] = []
    for name, members in groups.items():
        for i in members:
            runs[i].system, runs[i].entrant = name, entrants[i]
        if len(members) == 1:
            continue
        labelled = all(explicit[i] == entrants[i] for i in members)
        if labelled or pool:
            poolings.append(Pooling(name, tuple(runs[i].name for i in members), "label" if labelled else "asked"))
            continue
        split: dict[tuple[Any, ...], list[int]] = {}
        for i in members:
            split.setdefault(evaluation[i], []).append(i)
        if len(split) == 1:  # one sweep's cells of one system, split by condition or run
            continue
        shown = [runs[cells[0]].folder if len(cells) == 1 else runs[cells[0]].sweep for cells in split.values()]
        for cells, folder in zip(split.values(), _folder_names(shown), strict=True):
            for i in cells:
                runs[i].system = f"{name} ({folder})"
                runs[i].entrant = f"{entrants[i]} ({folder})"
    return poolings


__all__ = [
    "AXIS_ORDER",
    "LABEL_JOIN",
    "NON_SYSTEM_AXES",
    "Pooling",
    "assign_systems",
    "axis_labels",
    "config_label",
    "planted_label",
    "set_name",
    "simulation_label",
]

"""Sweeps: one base pipeline expanded over axes into cells, run with one cache and one image store.

A sweep YAML (see :class:`povagent.config.pipeline.SweepConfig`) names a base pipeline, axes
(``model``, ``backend``, ``strategy``, ``parser``, ``conditions``, ``runs``) and optional named
overrides. Their cartesian product gives the cells; each cell is an ordinary pipeline whose
output is ``<sweep output>/<cell name>`` and whose cache is the sweep's. ``sweep.json`` in the
sweep folder indexes the cells (axes, folder, status, overall score) and is rewritten after
each cell, so an interrupted sweep resumes cell by cell and key by key.

A dry run prints the cells, the requests still to make (finished keys subtracted) and a rough
token estimate, without calling any model. This module must not render tables.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from povagent.config.pipeline import (
    REPLACED_WHOLE,
    ComponentSpec,
    ConfigSource,
    PipelineConfig,
    SweepConfig,
    deep_merge,
    load_sweep,
    pipeline_from_source,
    plugin_paths_from_the_yaml_folder,
)
from povagent.dataset.protocol import EvaluationSet
from povagent.engine.cache import ResponseCache
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, TextPart
from povagent.interfaces import declares_turns, whole_answer_placeholders
from povagent.plugins import PluginHost, get_plugin_host, unknown_name_message
from povagent.run.pending import ensure_dataset, pending_keys
from povagent.run.progress import make_progress
from povagent.run.runner import PipelineRun, RunResult, create_components

SWEEP_INDEX = "sweep.json"

#: Rough prompt tokens per 512x512 image (ViT patches of 28 px); dry-run estimates only.
TOKENS_PER_IMAGE_PIXEL = 1.0 / (28 * 28)


@dataclass
class Cell:
    """One point of the sweep: its name, the axis values that made it, and its pipeline."""

    name: str
    axes: dict[str, str]
    config: PipelineConfig


@dataclass
class TurnCount:
    """What one turn of a cell's strategy still has to do (see :meth:`Strategy.plan_turns`)."""

    turn: int
    requests: int
    prompt_tokens: int
    max_completion_tokens: int
    note: str = ""


@dataclass
class DryRunCell:
    """What a cell still has to do: totals over the turns, and each sent turn's counts."""

    name: str
    n_total: int
    n_done: int
    requests: int
    prompt_tokens: int
    max_completion_tokens: int
    turns: list[TurnCount] = field(default_factory=list)
    #: False when the strategy overrides ``solve`` without ``plan_turns``: later turns unknown.
    turns_declared: bool = True


@dataclass
class SweepResult:
    """What :func:`run_sweep` returns."""

    output: Path
    cells: list[Cell]
    results: dict[str, RunResult] = field(default_factory=dict)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-") or "x"


def _spec_label(spec: Any) -> str:
    model = spec.options.get("model") if isinstance(spec.options, dict) else None
    return _slug(f"{spec.name}-{model}" if isinstance(model, str) else spec.name)


def _axis_values(sweep: SweepConfig) -> list[tuple[str, list[tuple[str, dict[str, Any]]]]]:
    """Each axis as ``(axis, [(label, partial pipeline), ...])`` in a fixed order."""
    a = sweep.axes
    axes: list[tuple[str, list[tuple[str, dict[str, Any]]]]] = []
    if a.model:
        axes.append(("model", [(_slug(m), {"model": m, "backend": None}) for m in a.model]))
    if a.backend:
        axes.append(("backend", [(_spec_label(s), {"backend": s.model_dump(), "model": None}) for s in a.backend]))
    if a.strategy:
        axes.append(("strategy", [(_spec_label(s), {"strategy": s.model_dump()}) for s in a.strategy]))
    if a.parser:
        axes.append(("parser", [(_spec_label(s), {"parser": s.model_dump()}) for s in a.parser]))
    if a.conditions:
        axes.append(("conditions", [(c.value, {"instances": {"conditions": [c.value]}}) for c in a.conditions]))
    if a.runs:
        axes.append(("runs", [(f"run{r}", {"runs": [r]}) for r in a.runs]))
    if sweep.overrides:
        axes.append(("override", [(_slug(name), part) for name, part in sweep.overrides.items()]))
    for axis, values in axes:
        labels = [label for label, _ in values]
        if len(set(labels)) != len(labels):
            # Same plugin twice with other options: number them so folders stay distinct.
            axes[axes.index((axis, values))] = (axis, [(f"{label}-{i}", part) for i, (label, part) in enumerate(values)])
    return axes


def _check_axis_names(sweep: SweepConfig, source: ConfigSource, host: PluginHost) -> None:
    problems = []
    checks: list[tuple[str, str, Sequence[str | ComponentSpec]]] = [("model", "profile", sweep.axes.model or []), ("backend", "backend", sweep.axes.backend or []),
              ("strategy", "strategy", sweep.axes.strategy or []), ("parser", "parser", sweep.axes.parser or [])]
    for axis, kind, values in checks:
        known = host.names(kind)
        for i, v in enumerate(values):
            name = v if isinstance(v, str) else v.name
            if name not in known:
                problems.append(f"{source.where(('axes', axis, i))}: axes.{axis}[{i}]: {unknown_name_message(kind, name, known)}")
    if problems:
        raise ConfigError("unknown plugin name(s):\n" + "\n".join(problems))


def expand_sweep(path: str | Path, *, host: PluginHost | None = None, strict: bool = False) -> tuple[SweepConfig, list[Cell]]:
    """Read a sweep YAML and expand it into validated cells (no request is made).

    ``strict`` makes every cell stop at a bad house or pair of its dataset instead of
    reporting it and going on.
    """
    sweep, source, base = load_sweep(path)
    if not isinstance(base.data, dict):
        raise ConfigError(f"{base.file}: the base pipeline must be a YAML mapping")
    plugins = base.data.get("plugins") or []
    if isinstance(plugins, list):
        # a relative .py path is read from the base pipeline's folder, as when it runs alone
        resolved = plugin_paths_from_the_yaml_folder(plugins, base.file)
        if resolved != plugins:
            base = ConfigSource(base.file, {**base.data, "plugins": resolved}, base.lines)
            plugins = resolved
    if host is None:
        try:
            host = get_plugin_host(plugins if isinstance(plugins, list) else [])
        except Exception as exc:
            raise ConfigError(f"{base.where(('plugins',))}: {exc}") from None
    _check_axis_names(sweep, source, host)
    cache = {"enabled": sweep.cache.enabled, "path": str(sweep.cache.path or sweep.output / "cache.sqlite")}
    axes = _axis_values(sweep)
    cells: list[Cell] = []
    for combo in itertools.product(*[values for _, values in axes]) if axes else [()]:
        name = "__".join(label for label, _ in combo) or "base"
        overrides: dict[str, Any] = {}
        for _, part in combo:
            overrides = deep_merge(overrides, part, REPLACED_WHOLE)
        overrides["output"] = str(sweep.output / name)
        overrides["cache"] = cache
        cell_source = ConfigSource(f"{base.file} (sweep cell {name})", base.data, base.lines)
        config = pipeline_from_source(cell_source, overrides=overrides, host=host)
        if strict:
            config = config.model_copy(update={"dataset": config.dataset.model_copy(update={"strict": True})})
        cells.append(Cell(name, {axis: label for (axis, _), (label, _) in zip(axes, combo)}, config))
    return sweep, cells


def dry_run(cells: list[Cell], *, host: PluginHost | None = None) -> list[DryRunCell]:
    """Requests still to make per cell and per turn (finished keys subtracted) and a rough
    token estimate, from the turns the strategy plans (:meth:`Strategy.plan_turns`).

    Tokens are estimated from one instance per condition: text at ~4 characters a token,
    images at ~1 token per 28x28 pixels, a placeholder for an earlier whole answer at that
    turn's ``max_tokens``; completions at each turn's ``max_tokens`` (an upper bound). A turn
    the strategy takes only sometimes is counted for every key (an upper bound too); a turn it
    works out itself is not a request.
    """
    datasets: dict[Any, EvaluationSet] = {}
    images = ImageStore()
    out: list[DryRunCell] = []
    for cell in cells:
        h = host or get_plugin_host(cell.config.plugins)
        ds = ensure_dataset(cell.config, datasets)
        total, done, pending = pending_keys(cell.config, ds)
        strategy = h.create("strategy", cell.config.strategy.name, cell.config.strategy.options)
        by_condition: dict[str, list[Any]] = {}
        for inst, _ in pending:
            by_condition.setdefault(str(inst.condition), []).append(inst)
        counts: dict[int, TurnCount] = {}
        for group in by_condition.values():
            planned = strategy.plan_turns(group[0], images)
            budgets = [t.request.generation.max_tokens or 0 for t in planned]
            for number, turn in enumerate(planned, start=1):
                if not turn.sent:
                    continue
                count = counts.setdefault(number, TurnCount(number, 0, 0, 0, turn.note))
                count.requests += len(group)
                count.prompt_tokens += math.ceil(_prompt_tokens(turn.request, images, budgets) * len(group))
                # no limit (None): the estimate counts none, so it is a lower bound for that turn
                count.max_completion_tokens += (turn.request.generation.max_tokens or 0) * len(group)
        turns = [counts[n] for n in sorted(counts)]
        out.append(
            DryRunCell(
                cell.name, total, done, sum(t.requests for t in turns), sum(t.prompt_tokens for t in turns),
                sum(t.max_completion_tokens for t in turns), turns, declares_turns(strategy),
            )
        )
    return out


def _prompt_tokens(request: Request, images: ImageStore, budgets: list[int]) -> float:
    """Rough prompt tokens of a planned request; a whole-answer placeholder counts as the
    budget (``max_tokens``) of the turn it stands for."""
    text = 0.0
    for m in request.messages:
        for p in m.parts:
            if isinstance(p, TextPart):
                text += len(p.text) / 4
                for turn in whole_answer_placeholders(p.text):
                    text += budgets[turn - 1] if turn <= len(budgets) else 0
    pixels = sum(images.info(h).width * images.info(h).height for h in request.image_hashes())
    return text + pixels * TOKENS_PER_IMAGE_PIXEL


def _write_index(output: Path, sweep_file: str, cells: list[Cell], status: dict[str, dict[str, Any]]) -> None:
    index = {
        "sweep": sweep_file,
        "output": str(output),
        "cells": [
            {"name": c.name, "axes": c.axes, "run_dir": str(c.config.output), "config_hash": c.config.config_hash(), **status.get(c.name, {"status": "pending"})}
            for c in cells
        ],
    }
    output.mkdir(parents=True, exist_ok=True)
    tmp = output / (SWEEP_INDEX + ".tmp")
    tmp.write_text(json.dumps(index, indent=2, default=str) + "\n", encoding="utf-8")
    os.replace(tmp, output / SWEEP_INDEX)


def run_sweep(
    path: str | Path,
    *,
    quiet: bool = False,
    retry_failed: bool = True,
    strict: bool = False,
    on_cell_done: Callable[[Cell, RunResult], None] | None = None,
) -> SweepResult:
    """Run every cell of a sweep in turn, sharing one response cache and one image store.

    ``strict``: stop at a bad house or pair of a dataset (default: report it and go on).
    """
    sweep, cells = expand_sweep(path, strict=strict)
    for cell in cells:
        # Every cell's plugin options (and image transport) are checked before the first
        # request of the first cell.
        backend = create_components(cell.config, get_plugin_host(cell.config.plugins)).backend
        backend.check_image_transport(cell.config.images.transport)
    output = Path(sweep.output)
    result = SweepResult(output, cells)
    status: dict[str, dict[str, Any]] = {}
    _write_index(output, str(path), cells, status)

    async def run_cells() -> None:
        first = cells[0].config
        images = ImageStore(max_bytes=first.images.max_mb * 1024 * 1024)
        cache_path = first.cache_path()
        cache = ResponseCache(cache_path) if cache_path is not None else None
        datasets: dict[Any, EvaluationSet] = {}
        try:
            for cell in cells:
                status[cell.name] = {"status": "running"}
                _write_index(output, str(path), cells, status)
                try:
                    run = PipelineRun(
                        cell.config,
                        dataset=ensure_dataset(cell.config, datasets),
                        images=images,
                        cache=cache,
                        progress=make_progress(cell.name, quiet=quiet),
                        retry_failed=retry_failed,
                    )
                    res = await run.run()
                except BaseException:
                    status[cell.name] = {"status": "interrupted"}
                    raise
                result.results[cell.name] = res
                status[cell.name] = {
                    "status": "interrupted" if res.interrupted else ("done" if res.summary["complete"] else "incomplete"),
                    "rows": res.summary["rows"],
                    "overall": res.summary["overall"],
                }
                if on_cell_done is not None:
                    on_cell_done(cell, res)
        finally:
            _write_index(output, str(path), cells, status)
            if cache is not None:
                cache.close()

    asyncio.run(run_cells())
    return result

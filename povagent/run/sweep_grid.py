"""A sweep's grid: the base pipeline expanded over the sweep's axes and named overrides into
cells (:func:`expand_sweep`), each an ordinary pipeline with its own output folder.

Reads the sweep YAML and checks every axis value names a registered plugin; runs nothing.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from povagent.config.models import ComponentSpec, PipelineConfig
from povagent.config.overrides import REPLACED_WHOLE, deep_merge
from povagent.config.pipeline import load_sweep, pipeline_from_source
from povagent.config.plugin_checks import checked_plugins
from povagent.config.sweep_models import SweepConfig
from povagent.config.yaml_reader import ConfigSource
from povagent.errors import ConfigError
from povagent.plugins import PluginHost, get_plugin_host, unknown_name_message


@dataclass
class Cell:
    """One point of the sweep: its name, the axis values that made it, and its pipeline."""

    name: str
    axes: dict[str, str]
    config: PipelineConfig


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
    checks: list[tuple[str, str, Sequence[str | ComponentSpec]]] = [
        ("model", "profile", sweep.axes.model or []),
        ("backend", "backend", sweep.axes.backend or []),
        ("strategy", "strategy", sweep.axes.strategy or []),
        ("parser", "parser", sweep.axes.parser or []),
    ]
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
        # the rule of povagent.config.plugin_rule, checked before anything is imported: a .py
        # path is read from the base pipeline's folder, as when it runs alone
        resolved = checked_plugins(plugins, base)
        if resolved != plugins:
            base = ConfigSource(base.file, {**base.data, "plugins": resolved}, base.lines, base.plugin_folder())
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
        cell_source = ConfigSource(f"{base.file} (sweep cell {name})", base.data, base.lines, base.plugin_folder())
        config = pipeline_from_source(cell_source, overrides=overrides, host=host)
        if strict:
            config = config.model_copy(update={"dataset": config.dataset.model_copy(update={"strict": True})})
        cells.append(Cell(name, {axis: label for (axis, _), (label, _) in zip(axes, combo)}, config))
    return sweep, cells

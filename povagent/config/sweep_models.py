"""The sweep schema: a base pipeline, the axes (and named overrides) it is expanded over into
cells, the response cache the cells share and the cluster they may run on.

Like :mod:`povagent.config.models`, whose pipeline models it builds on, it is data: it must not
read files (:mod:`povagent.config.yaml_reader`), expand the grid (:mod:`povagent.run.sweep_grid`)
or run anything.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import Field, field_validator

from povagent.config.cluster_spec import yaml_cluster_spec  # pure: no Dask import
from povagent.config.models import MAX_RUNS, CacheSpec, ComponentSpec, InstanceFilter, StrictModel, a_folder_path
from povagent.dataset.release_models import Condition
from povagent.errors import ClusterError


class SweepAxes(StrictModel):
    """Lists to take the cartesian product of; a missing axis keeps the base's value."""

    model: list[str] | None = None
    backend: list[ComponentSpec] | None = None
    strategy: list[ComponentSpec] | None = None
    parser: list[ComponentSpec] | None = None
    conditions: list[Condition] | None = None
    runs: list[int] | None = None

    @field_validator("conditions", mode="before")
    @classmethod
    def _condition_names(cls, value: Any) -> Any:
        return InstanceFilter._condition_names(value)

    @field_validator("runs")
    @classmethod
    def _run_indices(cls, value: list[int] | None) -> list[int] | None:
        if value is not None and any(r < 0 for r in value):
            raise ValueError("run indices must be >= 0")
        if value is not None and len(value) > MAX_RUNS:
            raise ValueError(f"at most {MAX_RUNS} run indices (got {len(value)})")
        return value


class SweepConfig(StrictModel):
    """A sweep: a base pipeline expanded over axes (and named overrides) into cells.

    ::

        base: pipeline_center.yaml   # path relative to this file, or an inline pipeline mapping
        output: runs/baselines       # one folder per cell under it, plus sweep.json
        axes:                        # cartesian product; each value overrides the base
          backend: [center, random, oracle]
          strategy: [basic, spatial-cot]
          conditions: [a, b, c]      # one cell per condition
          runs: [0, 1, 2]            # one cell per run index
        overrides:                   # named partial pipelines, one more axis (optional)
          short-answers: {strategy: {name: basic, options: {max_tokens: 64}}}
        cache: runs/cache.sqlite     # shared by every cell (default <output>/cache.sqlite)
        cluster: local:4             # optional: each cell a task on Dask, local:N only; a
                                     # scheduler's address is given with --cluster (docs/how-to/cluster.md)
    """

    base: str | dict[str, Any]
    output: Path
    axes: SweepAxes = Field(default_factory=SweepAxes)
    overrides: dict[str, dict[str, Any]] = Field(default_factory=dict)
    cache: CacheSpec = Field(default_factory=CacheSpec)
    cluster: str | None = None

    @field_validator("cluster")
    @classmethod
    def _cluster_spec(cls, value: str | None) -> str | None:
        if value is not None:
            try:
                yaml_cluster_spec(value)
            except ClusterError as exc:
                raise ValueError(str(exc).removeprefix("--cluster ")) from None
        return value

    @field_validator("output")
    @classmethod
    def _output_is_a_folder(cls, value: Path) -> Path:
        return a_folder_path(value)

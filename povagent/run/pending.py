"""Which keys a pipeline covers and which of them still need running.

A key is ``instance id#run``. :func:`select_instances` picks the instances a pipeline covers;
:func:`plan_keys` reads the run folder once and says which keys are done, which failed for
infrastructure reasons (re-attempted by default), and which are pending, in house-major order.
The runner and dry runs (``sweep --dry-run``) both call :func:`plan_keys`, so they agree.
"""

from __future__ import annotations

import json
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from povagent.config.models import PipelineConfig
from povagent.dataset.instances import Instance, row_key
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import ConfigError
from povagent.results.rows import RowStatus, iter_rows
from povagent.run.components import pipeline_hash

#: The results file of a run folder.
RESULTS = "results.jsonl"


def select_instances(dataset: EvaluationSet, config: PipelineConfig) -> list[Instance]:
    """The instances a pipeline covers, in dataset order (grouped by house).

    Filter by conditions, directions and houses; then ``sample`` N with ``seed`` (kept in
    dataset order so each house's frames are read together); then keep the first ``limit``.
    """
    f = config.instances
    if f.houses:
        unknown = sorted(set(f.houses) - set(dataset.houses))
        if unknown:
            raise ConfigError(f"instances.houses: unknown house id(s) {', '.join(unknown)} in {dataset.root}")
    chosen = list(dataset.instances(f.conditions, f.directions, f.houses))
    if f.sample is not None and f.sample < len(chosen):
        keep = sorted(random.Random(f.seed).sample(range(len(chosen)), f.sample))
        chosen = [chosen[i] for i in keep]
    if f.limit is not None:
        chosen = chosen[: f.limit]
    return chosen


def house_major(keys: list[tuple[Instance, int]]) -> list[tuple[Instance, int]]:
    """``keys`` ordered house by house, each house's exploration-frame keys (A/B) first.

    The official prompt puts a house's 30 frames first, so a server with automatic prefix
    caching (vLLM's default) reuses that prefix only when the house's A/B requests arrive close
    together; the Given keys of the house (one observer view each) follow. Within a group the
    given order is kept (stable), so a resumed run keeps the order of a fresh one.
    """
    first_seen: dict[str, int] = {}
    for inst, _ in keys:
        first_seen.setdefault(inst.house_id, len(first_seen))
    return sorted(keys, key=lambda k: (first_seen[k[0].house_id], not k[0].answers_a_frame))


@dataclass
class KeyPlan:
    """The keys of one pipeline in its run folder."""

    #: each key of the selection
    wanted: set[str]
    done: set[str]
    #: keys whose last row is ``infra_error`` (pending again unless they are kept)
    failed: set[str]
    pending: list[tuple[Instance, int]]

    @property
    def n_total(self) -> int:
        """Keys the pipeline covers."""
        return len(self.wanted)


def plan_keys(
    config: PipelineConfig,
    instances: list[Instance],
    *,
    config_hash: str | None = None,
    retry_failed: bool = True,
) -> KeyPlan:
    """Read ``config.output``'s results once and plan the keys of ``instances`` x runs.

    A row of another pipeline (a different ``config_hash``) is refused with a clear message:
    appending to it would mix two pipelines in one file. With ``retry_failed`` (the default) a
    key whose row is ``infra_error`` is pending again (its old row is dropped when the run
    starts); parse errors are answers and stay done. Nothing of a done row is kept but its key:
    the summary reads the rows back at the run's end.
    """
    runs = config.run_indices
    ordered = house_major([(i, r) for i in instances for r in runs])
    wanted = {row_key(i.id, r) for i, r in ordered}
    run_dir = Path(config.output)
    done: set[str] = set()
    failed: set[str] = set()
    for row in iter_rows(run_dir / RESULTS):
        if row.config_hash and config_hash is None:  # made once, and only for a folder with rows
            config_hash = pipeline_hash(config)
        if row.config_hash and row.config_hash != config_hash:
            raise ConfigError(
                f"{run_dir}: holds rows of a different pipeline (config hash {row.config_hash}, this one "
                f"{config_hash}: backend, strategy, parser or scorers differ); choose another output folder"
            )
        if row.key not in wanted:
            continue
        done.add(row.key)
        if row.status is RowStatus.INFRA_ERROR:
            failed.add(row.key)
        else:
            failed.discard(row.key)
    if retry_failed:
        done -= failed
    pending = [(i, r) for i, r in ordered if row_key(i.id, r) not in done]  # house-major, as a fresh run's
    return KeyPlan(wanted=wanted, done=done, failed=failed, pending=pending)


def prepare_dataset(config: PipelineConfig) -> EvaluationSet:
    """Load the dataset, generating it first for a ``generate:`` spec whose folder is empty, or
    fetching it first for a ``hub:`` spec (which then names the local copy); its instances are
    the ones the pipeline's ``task:`` asks (:func:`povagent.tasks.task_set.for_task`)."""
    return asked_by(config, _loaded_dataset(config))


def asked_by(config: PipelineConfig, dataset: EvaluationSet) -> EvaluationSet:
    """``dataset`` as the pipeline's task asks it (the set itself for the point task)."""
    if config.task.is_point_task:
        return dataset
    from povagent.tasks.task_set import for_task  # the generator's scene: only when a task asks

    return for_task(dataset, config.task)


def _loaded_dataset(config: PipelineConfig) -> EvaluationSet:
    from povagent.config.pipeline import resolve_hub_dataset

    spec = resolve_hub_dataset(config).dataset
    if spec.generate is not None:
        g = spec.generate
        if not (g.out / "meta.json").is_file():  # none yet, or an interrupted one: generating resumes it
            from povagent.generate import generate_dataset  # heavy (trimesh): only when asked

            generate_dataset(
                g.out,
                houses=g.houses,
                seed=g.seed,
                frames=g.frames,
                judge=g.judge.name,
                judge_options=g.judge.options,
                plugins=config.plugins,
            )
    from povagent.dataset.evaluation_set import open_evaluation_set

    return open_evaluation_set(spec.root, strict=spec.strict, format=spec.format, images=spec.images, options=spec.options, plugins=config.plugins)


def ensure_dataset(config: PipelineConfig, loaded: dict[Any, EvaluationSet] | None = None) -> EvaluationSet:
    """The config's dataset, loaded once per folder (and strictness) when ``loaded`` is shared
    (sweeps)."""
    from povagent.config.pipeline import resolve_hub_dataset

    options = json.dumps(config.dataset.options, sort_keys=True, default=str) if config.dataset.options else None
    key = (Path(resolve_hub_dataset(config).dataset.root).resolve(), config.dataset.strict, config.dataset.format, options)
    if loaded is not None and key in loaded:
        return asked_by(config, loaded[key])
    ds = _loaded_dataset(config)
    if loaded is not None:
        loaded[key] = ds
    return asked_by(config, ds)


def pending_keys(config: PipelineConfig, dataset: EvaluationSet, *, retry_failed: bool = True) -> tuple[int, int, list[tuple[Instance, int]]]:
    """``(n_total, n_done, pending)`` for a pipeline, without running anything (dry runs).

    Planned exactly as a run would plan it (:func:`plan_keys`)."""
    plan = plan_keys(config, select_instances(dataset, config), retry_failed=retry_failed)
    return plan.n_total, len(plan.done), plan.pending

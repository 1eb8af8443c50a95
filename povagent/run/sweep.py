"""Sweeps: one base pipeline expanded over axes into cells, run with one cache and one image store.

A sweep YAML (see :class:`povagent.config.sweep_models.SweepConfig`) names a base pipeline, axes
(``model``, ``backend``, ``strategy``, ``parser``, ``conditions``, ``runs``) and optional named
overrides. Their cartesian product gives the cells; each cell is an ordinary pipeline whose
output is ``<sweep output>/<cell name>`` and whose cache is the sweep's. ``sweep.json`` in the
sweep folder indexes the cells (axes, folder, status, overall score) and is rewritten after
each cell, so an interrupted sweep resumes cell by cell and key by key.

The cells come from :mod:`povagent.run.sweep_grid`; a dry run (:mod:`povagent.run.sweep_estimate`)
prints them with the requests still to make, without calling any model. This module must not
render tables.

On a cluster (``cluster:`` in the YAML, or ``cluster=``) each cell is one task: :func:`run_cell`,
a plain function of one cell that resumes from the cell's journal under its folder lock, so it
can be run twice, or again after its worker died, and give the same rows. Only
:mod:`povagent.cluster` knows the engine; this module hands it those functions, watches the
cells' journals for progress (:class:`JournalWatch`) and writes ``sweep.json`` itself.
"""

from __future__ import annotations

import asyncio
import functools
import json
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Collection

from povagent.config.models import PipelineConfig
from povagent.config.remote_code import remote_code_granted
from povagent.dataset.set_interface import EvaluationSet
from povagent.engine.cache import ResponseCache, merge_shards
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.files.confined_write import ConfinedFolder, write_inside
from povagent.files.folder_lock import folder_lock
from povagent.plugins import get_plugin_host
from povagent.results.output_check import check_output_text
from povagent.results.summary_json import summary_json_text
from povagent.run.pending import RESULTS, ensure_dataset, plan_keys, select_instances
from povagent.run.progress import QuietProgress, RunProgress, make_progress
from povagent.run.run_folder import claim_folder
from povagent.run.run_result import RunResult
from povagent.run.runner import PipelineRun, answering_model, create_components
from povagent.run.stop_signals import cancelled_on_stop
from povagent.run.sweep_grid import Cell, expand_sweep

SWEEP_INDEX = "sweep.json"
#: A cell's own response-cache file on a cluster (see :mod:`povagent.engine.cache`, shards),
#: folded into the sweep's cache by the client when the cells are done.
CELL_CACHE_SHARD = "cache-shard.sqlite"

@dataclass
class SweepResult:
    """What :func:`run_sweep` returns."""

    output: Path
    cells: list[Cell]
    results: dict[str, RunResult] = field(default_factory=dict)
    #: cells that raised instead of finishing (on a cluster): name -> the error, in one line
    failed: dict[str, str] = field(default_factory=dict)


def _write_index(
    output: Path, sweep_file: str, cells: list[Cell], status: dict[str, dict[str, Any]], models: dict[str, tuple[str, str | None]]
) -> None:
    """Write ``sweep.json``: every cell with its axes, folder, model (and profile) and status."""
    index = {
        "sweep": sweep_file,
        "output": str(output),
        "cells": [
            {
                "name": c.name,
                "axes": c.axes,
                "run_dir": str(c.config.output),
                "config_hash": c.config.config_hash(),
                "model": models[c.name][0],
                "profile": models[c.name][1],
                **status.get(c.name, {"status": "pending"}),
            }
            for c in cells
        ],
    }
    text = summary_json_text(index, indent=2, default=str)
    check_output_text("sweep", text, output / SWEEP_INDEX)
    write_inside(output, SWEEP_INDEX, text + "\n")


def cell_status(res: RunResult) -> dict[str, Any]:
    """A finished cell's entry in ``sweep.json`` (:class:`~povagent.run.sweep_index.SweepCell`'s
    status, row counts and overall cell), from its run's summary."""
    summary = res.summary
    return {
        "status": "interrupted" if res.interrupted else ("done" if summary.complete else "incomplete"),
        "rows": summary.rows.model_dump() if summary.rows is not None else None,
        "overall": summary.overall.model_dump(exclude_unset=True),
    }


def run_sweep(
    path: str | Path,
    *,
    quiet: bool = False,
    retry_failed: bool = True,
    strict: bool = False,
    on_cell_done: Callable[[Cell, RunResult], None] | None = None,
    cluster: Any = None,
    progress: RunProgress | None = None,
    notify: Callable[[str], None] | None = None,
    trust_remote_code: bool = False,
) -> SweepResult:
    """Run every cell of a sweep in turn, sharing one response cache and one image store.

    ``strict``: stop at a bad house or pair of a dataset (default: report it and go on).

    ``cluster`` (``local:N``, a scheduler's ``tcp://`` address, or a ``distributed.Client``;
    default: the YAML's ``cluster:`` key) runs each cell as a task on a Dask cluster instead;
    ``progress`` then counts the rows of every cell (default: a bar on a terminal), ``notify``
    hears the dashboard's address and what the storage check found, and a cell that raises is
    recorded in :attr:`SweepResult.failed` while the others finish. Without a cluster Dask is
    never imported.

    ``trust_remote_code``: the cells' checkpoints may run their own code (the caller's grant;
    a sweep YAML cannot give it, see :mod:`povagent.config.remote_code`).
    """
    sweep, cells = expand_sweep(path, strict=strict)
    models: dict[str, tuple[str, str | None]] = {}
    if cluster is None:
        cluster = sweep.cluster
    for cell in cells:
        # Every cell's plugin options (and image transport) are checked before the first
        # request of the first cell.
        with remote_code_granted(trust_remote_code):
            backend = create_components(cell.config, get_plugin_host(cell.config.plugins)).backend
        backend.check_image_transport(cell.config.images.transport)
        models[cell.name] = answering_model(backend)
    output = Path(sweep.output)
    claim_folder(output, "sweep")  # someone's folder (or a read-only one) is refused before any write
    for cell in cells:  # a cell's folder planted as a link to elsewhere is refused, not run into
        if Path(cell.config.output).is_relative_to(output):
            ConfinedFolder(output, Path(cell.config.output).relative_to(output)).close()
    result = SweepResult(output, cells)
    status: dict[str, dict[str, Any]] = {}
    _write_index(output, str(path), cells, status, models)
    if cluster is not None:
        _run_on_cluster(cluster, str(path), result, status, models, retry_failed=retry_failed, on_cell_done=on_cell_done,
                        trust_remote_code=trust_remote_code,
                        progress=progress or make_progress(f"sweep on {cluster}", quiet=quiet), notify=notify or (lambda _: None))
        return result

    async def run_cells() -> None:
        with cancelled_on_stop():  # a SIGTERM between cells lands at an await too
            await run_each_cell()

    async def run_each_cell() -> None:
        first = cells[0].config
        images = ImageStore(max_bytes=first.images.max_mb * 1024 * 1024)
        cache_path = first.cache_path()
        cache = ResponseCache(cache_path) if cache_path is not None else None
        datasets: dict[Any, EvaluationSet] = {}
        try:
            for cell in cells:
                status[cell.name] = {"status": "running"}
                _write_index(output, str(path), cells, status, models)
                try:
                    run = PipelineRun(
                        cell.config,
                        dataset=ensure_dataset(cell.config, datasets),
                        images=images,
                        cache=cache,
                        progress=make_progress(cell.name, quiet=quiet),
                        retry_failed=retry_failed,
                        trust_remote_code=trust_remote_code,
                    )
                    res = await run.run()
                except BaseException:
                    status[cell.name] = {"status": "interrupted"}
                    raise
                result.results[cell.name] = res
                status[cell.name] = cell_status(res)
                if on_cell_done is not None:
                    on_cell_done(cell, res)
        finally:
            _write_index(output, str(path), cells, status, models)
            if cache is not None:
                cache.close()

    asyncio.run(run_cells())
    return result


# -- on a cluster ---------------------------------------------------------------------------------
def anchored(config: PipelineConfig) -> PipelineConfig:
    """``config`` with every path made absolute from here (a worker's working folder is its own).

    Copied, not validated again: a resolved pipeline holds both its model profile and the
    backend it resolved to, which a fresh pipeline may not.
    """

    def absolute(value: Path | None) -> Path | None:
        return None if value is None else Path(value).absolute()

    ds = config.dataset
    dataset = ds.model_copy(update={"path": absolute(ds.path)})
    if ds.generate is not None:
        dataset = dataset.model_copy(update={"generate": ds.generate.model_copy(update={"out": absolute(ds.generate.out)})})
    return config.model_copy(
        update={
            "output": absolute(config.output),
            "dataset": dataset,
            "cache": config.cache.model_copy(update={"path": absolute(config.cache.path)}),
            "images": config.images.model_copy(update={"cache_dir": absolute(config.images.cache_dir)}),
            "plugins": [str(Path(p).absolute()) if p.endswith(".py") else p for p in config.plugins],
        }
    )


#: What the cells of one sweep share in one worker process and thread, as the cells of a sweep
#: on one machine share it: ``(sweep id, thread) -> (loaded datasets, image store)``. Only the
#: latest sweep's entry per thread is kept, so a long-lived worker holds one sweep's images.
_SHARED: dict[tuple[str, int], tuple[dict[Any, EvaluationSet], ImageStore]] = {}


def _shared(sweep_id: str, config: PipelineConfig) -> tuple[dict[Any, EvaluationSet], ImageStore]:
    import threading

    thread = threading.get_ident()
    key = (sweep_id, thread)
    if key not in _SHARED:
        for old in [k for k in _SHARED if k[1] == thread]:
            del _SHARED[old]
        _SHARED[key] = ({}, ImageStore(max_bytes=config.images.max_mb * 1024 * 1024))
    return _SHARED[key]


def run_cell(
    config: PipelineConfig, *, retry_failed: bool = True, sweep_id: str | None = None, trust_remote_code: bool = False
) -> RunResult:
    """One sweep cell, start to end or from where its journal stopped: a cluster's unit of work.

    Plain and idempotent: the rows go through the cell's journal under its folder lock, so a
    second run (a retry after a worker died) appends only the missing keys. New answers go to
    the cell's own cache shard, the sweep's cache is read beside it (see
    :mod:`povagent.engine.cache`); the client merges the shards. Cells given the same
    ``sweep_id`` in one process share their loaded datasets and image store (as on one
    machine), so a worker reads a house's frames once per sweep, not once per cell. Nothing is
    shown: progress is read from the journal by the client.
    """
    main = config.cache_path()
    claim_folder(Path(config.output), "run")  # marked ours before the cache shard is made in it
    cache = ResponseCache(Path(config.output) / CELL_CACHE_SHARD, read_also=main) if main is not None else None
    datasets, images = _shared(sweep_id, config) if sweep_id is not None else ({}, None)
    try:
        run = PipelineRun(config, dataset=ensure_dataset(config, datasets), images=images, cache=cache,
                          progress=QuietProgress(), retry_failed=retry_failed, trust_remote_code=trust_remote_code)
        return asyncio.run(run.run())
    finally:
        if cache is not None:
            cache.close()


class JournalWatch:
    """Rows finished in the cells' journals, as the client reads them (progress on a cluster).

    Each cell's ``results.jsonl`` is read from where the last look stopped; only complete lines
    count, each key once (a journal rewritten to retry failed keys is read again from its start,
    its kept keys already counted). Cheap: a ``stat`` per cell and the new bytes.
    """

    def __init__(self) -> None:
        self._files: dict[Path, list[Any]] = {}  # path -> [inode, offset, wanted keys, counted keys]

    def watch(self, run_dir: Path, wanted: Collection[str], counted: set[str]) -> None:
        """Follow ``run_dir``'s journal: ``wanted`` keys count, ``counted`` are counted already."""
        path = Path(run_dir) / RESULTS
        self._files[path] = [None, 0, wanted, set(counted)]

    def poll(self) -> list[str]:
        """The status of each row finished since the last poll."""
        finished: list[str] = []
        for path, state in self._files.items():
            try:
                st = path.stat()
            except OSError:
                continue
            if st.st_ino != state[0]:
                state[0], state[1] = st.st_ino, 0
            if st.st_size <= state[1]:
                state[1] = min(state[1], st.st_size)
                continue
            with open(path, "rb") as fh:
                fh.seek(state[1])
                data = fh.read(st.st_size - state[1])
            end = data.rfind(b"\n")
            if end < 0:
                continue
            state[1] += end + 1
            for line in data[: end + 1].splitlines():
                try:
                    row = json.loads(line)
                    key, row_status = row["key"], str(row["status"])
                except (ValueError, KeyError, TypeError):
                    continue  # not a row: the runner reports such a line itself
                if key in state[2] and key not in state[3]:
                    state[3].add(key)
                    finished.append(row_status)
        return finished


def _run_on_cluster(
    cluster: Any,
    sweep_file: str,
    result: SweepResult,
    status: dict[str, dict[str, Any]],
    models: dict[str, tuple[str, str | None]],
    *,
    retry_failed: bool,
    on_cell_done: Callable[[Cell, RunResult], None] | None,
    progress: RunProgress,
    notify: Callable[[str], None],
    trust_remote_code: bool = False,
) -> None:
    """Every cell as a task on ``cluster``; ``sweep.json``, progress and the cache stay here."""
    from povagent.cluster.sweep_tasks import CellTask, run_cell_tasks  # the one room that knows Dask

    cells, output = result.cells, result.output
    for cell in cells:
        if cell.config.images.transport == "http":
            raise ConfigError(
                f"cell {cell.name}: images.transport: http serves images from one port of one process; on a "
                "cluster every cell would bind it: use transport: file (storage the model server reads) or inline"
            )
    by_name = {c.name: c for c in cells}
    watch = JournalWatch()
    sweep_id = uuid.uuid4().hex
    tasks: list[CellTask] = []
    datasets: dict[Any, EvaluationSet] = {}
    total = done = 0
    for cell in cells:
        config = anchored(cell.config)
        dataset = ensure_dataset(config, datasets)  # fetched or generated here, once, before any task
        plan = plan_keys(config, select_instances(dataset, config), retry_failed=retry_failed)
        watch.watch(config.output, plan.wanted, plan.done)
        total, done = total + plan.n_total, done + len(plan.done)
        tasks.append(CellTask(cell.name, functools.partial(
            run_cell, config, retry_failed=retry_failed, sweep_id=sweep_id, trust_remote_code=trust_remote_code), dataset.root))
    main_cache = cells[0].config.cache_path()
    _merge_cell_caches(main_cache, cells, notify)  # shards an interrupted sweep left behind

    def ticked() -> None:
        for row_status in watch.poll():
            progress.advance(row_status)

    def finished(name: str, res: RunResult | None, error: str | None) -> None:
        ticked()
        cell = by_name[name]
        if res is None:
            result.failed[name] = error or "failed"
            status[name] = {"status": "failed", "error": error}
        else:
            result.results[name] = res
            status[name] = cell_status(res)
        _write_index(output, sweep_file, cells, status, models)
        if res is not None and on_cell_done is not None:
            on_cell_done(cell, res)

    for cell in cells:
        status[cell.name] = {"status": "running"}
    progress.start(total, done)
    try:
        run_cell_tasks(cluster, tasks, output=Path(output).absolute(), on_done=finished, on_tick=ticked, notify=notify)
    finally:
        progress.stop()
        for name, state in status.items():
            if state.get("status") == "running":
                status[name] = {"status": "interrupted"}
        _write_index(output, sweep_file, cells, status, models)
        _merge_cell_caches(main_cache, cells, notify)


def _merge_cell_caches(main: Path | None, cells: list[Cell], notify: Callable[[str], None]) -> None:
    """Fold the cells' cache shards into the sweep's cache (no shard: nothing to do).

    A shard is merged only under its cell's folder lock: a cell still running somewhere (a
    worker left behind by a lost scheduler, a cell an interrupted client did not wait for) keeps
    writing its shard, which is merged by a later run instead.
    """
    shards = [(Path(c.config.output), Path(c.config.output) / CELL_CACHE_SHARD) for c in cells]
    if main is None or not any(shard.is_file() for _, shard in shards):
        return
    with ResponseCache(main) as cache:
        for run_dir, shard in shards:
            if not shard.is_file():
                continue
            try:
                with folder_lock(run_dir):
                    _, problems = merge_shards(cache, [shard])
            except ConfigError:
                continue  # the cell is running elsewhere: its shard is merged by a later run
            for problem in problems:
                notify(f"warning: {problem}")

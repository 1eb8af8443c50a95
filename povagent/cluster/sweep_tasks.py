"""Sweep cells as Dask tasks: one task per cell, collected by the client.

Why one task per cell: a cell is already the unit that resumes. Its runner loads the dataset
once, keeps one image store, holds the cell's folder lock and appends each finished row to the
cell's journal, so a task run twice, or run again on another worker after its worker died,
appends only the keys still missing. Splitting a cell's keys over tasks would need several
journals per cell and a merge, for parallelism a sweep of many cells already has.

What a task may not do: decide anything about the sweep. ``sweep.json``, progress and the
response cache's merge stay on the client (:mod:`povagent.run.sweep`); this module only starts
the tasks, checks once that the workers see the run folder, and reports each cell's end.

Failures: a cell that raises is retried once (``CELL_RETRIES``: a folder lock still held by a
worker the scheduler gave up on, a storage hiccup), then reported with its error while the other
cells go on. A worker that dies mid-cell is the scheduler's to handle: the cell moves to another
worker (at most ``distributed.scheduler.allowed-failures`` times, 3 by default, then
``KilledWorker``). A scheduler that goes away ends the sweep with :class:`ClusterError`; every
row written so far is in the journals, so the same command resumes.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from povagent.cluster.client import cluster_client, dashboard_link
from povagent.cluster.storage import probe_storage
from povagent.errors import ClusterError

#: Automatic re-runs of a cell that raised (worker deaths are counted by the scheduler).
CELL_RETRIES = 1
#: Seconds between two looks at the journals while cells run.
POLL_S = 0.25
#: Seconds the client waits for a first worker to join an existing scheduler.
FIRST_WORKER_TIMEOUT_S = 60


@dataclass(frozen=True)
class CellTask:
    """A sweep cell as the engine sees it: a name and a plain function of no argument."""

    name: str
    run: Callable[[], Any]
    #: The cell's dataset folder, which every worker must see too.
    dataset_root: Path


def check_storage(client: Any, output: Path, datasets: Sequence[Path]) -> str:
    """Check once that every worker reads and writes ``output`` and sees ``datasets``.

    The client writes a probe file with a random token into ``output``; each worker reads it
    back and writes one of its own, which the client then reads. Raises :class:`ClusterError`
    naming the workers that cannot (the run folder must be on storage every worker sees: NFS,
    Lustre, a shared volume); returns a one-line account of what was found.
    """
    found = probe_storage(client, output, datasets)
    if not found.shared:
        cannot = found.blind + found.read_only
        raise ClusterError(
            f"{output}: worker(s) {', '.join(cannot)} cannot "
            f"{'read' if found.blind else 'write'} this folder as this machine sees it; a sweep on a cluster "
            "needs its output folder on storage every worker sees (NFS, Lustre, a shared volume) at the same path"
        )
    if found.missing:
        raise ClusterError(f"dataset folder not found on worker {found.missing[0]}; every worker must see the dataset at the same path")
    return f"storage: all {found.workers} worker(s) on {found.hosts} host(s) read and write {output}"


def run_cell_tasks(
    cluster: Any,
    tasks: Sequence[CellTask],
    *,
    output: Path,
    on_done: Callable[[str, Any, str | None], None],
    on_tick: Callable[[], None],
    notify: Callable[[str], None],
) -> None:
    """Run each task on ``cluster`` (a ``--cluster`` value or a ``distributed.Client``).

    ``on_done(name, result, None)`` or ``on_done(name, None, error)`` is called on this thread
    as each cell ends; ``on_tick()`` every ``POLL_S`` seconds meanwhile; ``notify`` gets the
    dashboard's address and the storage check's finding.
    """
    import logging

    client_log = logging.getLogger("distributed.client")
    level = client_log.level
    try:
        with cluster_client(cluster) as client:
            assert client is not None
            try:
                client.wait_for_workers(1, timeout=FIRST_WORKER_TIMEOUT_S)
            except TimeoutError:
                raise ClusterError(f"no Dask worker joined the scheduler at {client.scheduler.address} within {FIRST_WORKER_TIMEOUT_S} s") from None
            link = dashboard_link(client)
            if link:
                notify(f"Dask dashboard: {link}")
            notify(check_storage(client, output, [t.dataset_root for t in tasks]))
            batch = uuid.uuid4().hex[:8]
            futures = {client.submit(task.run, key=f"povagent-cell-{batch}-{task.name}", pure=False, retries=CELL_RETRIES): task.name for task in tasks}
            _collect(client, futures, on_done, on_tick)
    finally:
        client_log.setLevel(level)  # quietened while a lost scheduler's client closed


def _collect(client: Any, futures: dict[Any, str], on_done: Callable[[str, Any, str | None], None], on_tick: Callable[[], None]) -> None:
    """Hand each finished future to ``on_done``; raise :class:`ClusterError` if the scheduler goes.

    Nothing here cancels a future, so a cancelled one means the scheduler went away (the client
    cancels every future it held when its connection drops).
    """
    from concurrent.futures import CancelledError

    from distributed import wait

    pending = set(futures)
    while pending:
        try:
            done, pending = wait(pending, timeout=POLL_S, return_when="FIRST_COMPLETED")
        except (TimeoutError, UnboundLocalError):
            # UnboundLocalError: distributed's sync() can raise it when its loop is interrupted
            # while a worker dies (dask/distributed#8514); nothing finished this round, look again
            done = set()
        except CancelledError:
            _scheduler_gone(client, sorted(futures[f] for f in pending))
        on_tick()
        for future in done:
            name = futures[future]
            if future.status == "finished":
                on_done(name, future.result(), None)
            elif future.status == "error":
                on_done(name, None, _one_line(future.exception()))
            else:
                _scheduler_gone(client, sorted(futures[f] for f in pending | {future}))


def _scheduler_gone(client: Any, unfinished: list[str]) -> None:
    """Raise the one-line :class:`ClusterError` of a scheduler that went away mid-sweep."""
    import logging

    # The client's own reconnection attempt logs a traceback when it is closed on the way out;
    # the message below says all there is to say.
    logging.getLogger("distributed.client").setLevel(logging.CRITICAL)
    shown = ", ".join(unfinished[:5]) + (", ..." if len(unfinished) > 5 else "")
    raise ClusterError(
        f"the Dask scheduler at {client.scheduler.address} went away with {len(unfinished)} cell(s) unfinished "
        f"({shown}); every row written so far is kept: start a scheduler (or choose another --cluster) and "
        "run the same command to resume"
    )


def _one_line(exc: BaseException | None) -> str:
    """An error as one line: its type and its message's first line."""
    if exc is None:
        return "failed"
    if type(exc).__name__ == "KilledWorker":
        return f"its worker died while running it, again and again (KilledWorker: {str(exc).splitlines()[0] if str(exc) else ''})"
    first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__

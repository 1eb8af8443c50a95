"""Generating a dataset's houses on a Dask cluster: one task per house, results handed back as made.

What it is for: ``generate_dataset(..., cluster=...)`` calls :func:`generate_on_cluster` with the
houses still missing. It probes once whether the workers see the output folder (a file written
here, read on every worker): when they do, each task writes its house straight into it
(``make_house``: staged and renamed into place); when they do not, each task makes its house in a
private folder and returns the files (``make_house_files``), which this process writes the same
way. A worker that dies mid-house loses nothing: the scheduler gives the task to another worker
(at most Dask's ``distributed.scheduler.allowed-failures`` times, then the house is reported as
failed) and the half-written copy never reaches ``artifacts/``. A house that raises comes back as
a recorded failure. A scheduler that goes away ends the call with one line: the houses finished so
far are on disk, and the same command resumes. What it must not do: decide anything about a
house's content (that is ``generate/``), or be imported without ``--cluster``.
"""

from __future__ import annotations

import os
import time
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import CancelledError
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from povagent.cluster.client import WORKER_LOG_LEVEL, cluster_client, dashboard_link
from povagent.cluster.storage import probe_storage
from povagent.errors import ClusterError, is_file_system_error
from povagent.generate.house_task import HouseFailure, HouseOutcome, make_house, make_house_files
from povagent.generate.judge import SurfaceJudge
from povagent.generate.record import PARTIAL, GenerationOptions, place_house_files

#: How long to wait for a first worker on a scheduler that has none yet (a queued batch job).
WORKER_WAIT_S = 120
#: How often the client checks that its scheduler is still there while houses render.
POLL_S = 1.0
#: How long the client may stay disconnected from its scheduler before the run is called lost.
SCHEDULER_GRACE_S = 10.0

_LOG: Any = None


def generate_on_cluster(
    cluster: Any,
    out: Path,
    options: GenerationOptions,
    pending: list[int],
    judge: SurfaceJudge,
    finished: Callable[[HouseOutcome], None],
    storage: str = "auto",
    notice: Callable[[str], None] | None = None,
) -> None:
    """Make the ``pending`` houses on ``cluster``; call ``finished`` with each outcome as it arrives.

    ``storage`` is ``"shared"``, ``"return"`` or ``"auto"`` (probe). Raises
    :class:`~povagent.errors.ClusterError` when the scheduler is unreachable or goes away.
    """
    say = notice or (lambda message: None)
    left = len(pending)

    def count_down(outcome: HouseOutcome) -> None:
        nonlocal left
        left -= 1
        finished(outcome)

    with cluster_client(cluster) as client, _scheduler_watch(_address(cluster, client), len(pending), lambda: left):
        assert client is not None
        address = _address(cluster, client)
        link = dashboard_link(client)
        if link:
            say(f"Dask dashboard: {link}")
        _wait_for_a_worker(client, address)
        mode = storage
        if storage == "auto":
            found = probe_storage(client, Path(out) / PARTIAL)
            mode = "shared" if found.shared else "return"
            if mode == "shared":
                say(f"storage: all {found.workers} workers read and write {out}: they write houses straight into it")
            else:
                say(
                    f"storage: {len(found.writers)} of {found.workers} workers read and write {out}: workers send "
                    "each house's files back and this machine writes them"
                )
        _run_houses(client, address, Path(out), options, pending, judge, count_down, mode)


def _address(cluster: Any, client: Any) -> str:
    """The scheduler's address for messages (known even when the scheduler is gone)."""
    if isinstance(cluster, str) and not cluster.startswith("local:"):
        return cluster
    try:
        return str(client.scheduler.address)
    except Exception:
        return str(cluster)


@contextmanager
def _scheduler_watch(address: str, total: int, left: Callable[[], int]) -> Iterator[None]:
    """Turn a connection lost mid-call (CommClosedError is an OSError) into one line saying what to do.

    A file that could not be written here (a full disk under the probe or a house sent back, a
    read-only folder) is an OSError too, but not a lost scheduler: it goes on as it is, for the
    caller to name the file and the error.
    """
    try:
        yield
    except (OSError, TimeoutError, CancelledError) as exc:
        if is_file_system_error(exc):
            raise
        raise _scheduler_gone(address, total, left()) from None


def run_house(out: Path, options: GenerationOptions, index: int, judge: SurfaceJudge) -> HouseOutcome:
    """The task for shared storage: ``make_house`` with a structured log line on the worker."""
    return _logged(index, options, lambda: make_house(out, options, index, judge))


def run_house_files(options: GenerationOptions, index: int, judge: SurfaceJudge) -> HouseOutcome:
    """The task for storage the workers cannot see: ``make_house_files`` (the files come back)."""
    return _logged(index, options, lambda: make_house_files(options, index, judge))


def _logged(index: int, options: GenerationOptions, make: Callable[[], HouseOutcome]) -> HouseOutcome:
    log = _worker_log()
    log.info("house started", index=index, seed=options.seed)
    start = time.perf_counter()
    outcome = make()
    if outcome.failure is not None:
        log.error("house failed", index=index, seed=options.seed, error=outcome.failure.error)
    else:
        log.info(
            "house done",
            index=index,
            seed=options.seed,
            kept=outcome.kept,
            cpu_s=round(outcome.cpu_seconds, 3),
            wall_s=round(time.perf_counter() - start, 3),
        )
    return outcome


def _worker_log() -> Any:
    """This worker process's structured logger (files/logs.py's format, on the worker's stderr).

    Its level is the Dask config key ``povagent.worker-log-level`` (default info; a
    ``LocalCluster`` started by ``--cluster local:N`` sets warning, since its workers print on the
    user's terminal).
    """
    global _LOG
    if _LOG is None:
        import dask

        from povagent.files.logs import RunLog

        level = str(dask.config.get(WORKER_LOG_LEVEL, default="info"))
        _LOG = RunLog(None, console=True, console_level=level, pid=os.getpid())
    return _LOG


def _wait_for_a_worker(client: Any, address: str) -> None:
    if client.scheduler_info().get("workers"):
        return
    try:
        client.wait_for_workers(1, timeout=WORKER_WAIT_S)
    except (TimeoutError, OSError):
        raise ClusterError(f"the Dask scheduler at {address} has no worker after {WORKER_WAIT_S} s: start workers for it") from None


def _run_houses(
    client: Any, address: str, out: Path, options: GenerationOptions, pending: list[int], judge: SurfaceJudge,
    finished: Callable[[HouseOutcome], None], mode: str,
) -> None:
    from distributed import KilledWorker, wait

    run = uuid.uuid4().hex[:8]
    futures = {}
    for index in pending:
        key = f"povagent-house-{index:05d}-{run}"
        if mode == "shared":
            future = client.submit(run_house, out, options, index, judge, key=key, pure=False)
        else:
            future = client.submit(run_house_files, options, index, judge, key=key, pure=False)
        futures[future] = index
    waiting = set(futures)
    lost_since: float | None = None
    while waiting:
        try:
            done, waiting = wait(waiting, timeout=POLL_S, return_when="FIRST_COMPLETED")
        except (TimeoutError, UnboundLocalError):
            # UnboundLocalError: distributed's sync() can raise it when its loop is interrupted
            # while a worker dies (dask/distributed#8514); nothing finished this round, look again
            done = set()
        if client.status != "running":
            # the client reconnects on its own for a while; a scheduler that stays away is gone
            lost_since = lost_since or time.monotonic()
            if time.monotonic() - lost_since > SCHEDULER_GRACE_S:
                raise _scheduler_gone(address, len(futures), len(waiting | done))
        else:
            lost_since = None
        for future in sorted(done, key=lambda f: futures[f]):
            index = futures[future]
            if future.status == "cancelled":
                raise _scheduler_gone(address, len(futures), len(waiting | done))
            try:
                outcome = future.result()
            except KilledWorker as exc:
                error = f"the workers running it died every time it was tried (Dask's allowed-failures): {exc}"
                outcome = HouseOutcome(index, failure=HouseFailure(index, options.seed, error))
            except Exception as exc:  # the task could not run at all (say, a judge plugin missing there)
                error = f"{type(exc).__name__}: {exc}"
                outcome = HouseOutcome(index, failure=HouseFailure(index, options.seed, error))
            if outcome.files is not None:
                outcome.record = place_house_files(out, index, outcome.files)
                outcome.files = None
            future.release()
            finished(outcome)


def _scheduler_gone(address: str, total: int, left: int) -> ClusterError:
    return ClusterError(
        f"lost the Dask scheduler at {address} with {left} of {total} houses unfinished: the finished "
        "houses are on disk; run the same command again to resume"
    )

"""A real Dask cluster on 127.0.0.1: ``dask scheduler`` and ``dask worker`` processes.

The fixture starts the processes with the venv's own ``dask`` command, waits until the scheduler
sees every worker, and stops them by their pids in ``finally``. Workers run without a nanny, so a
worker killed with SIGKILL stays dead (the scheduler must move its tasks to the other worker).
Every process has a bounded lifetime (``--idle-timeout`` and ``--lifetime``), so nothing outlives a
crashed test session by long.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

#: Longest a test cluster may live, in case a test session dies without its teardown.
LIFETIME = "600s"

#: The environment of every scheduler and worker the tests start. Dask's own housekeeping is
#: slowed or off where no test reads it: the event-loop health tick (50 a second, a warning
#: when the loop blocks), the system and memory monitors (dashboard figures; memory-limit
#: spilling that tiny test tasks never reach) and the workers' statistical profiler (a stack
#: sample every 10 ms). Idle, a scheduler and two workers cost about 0.33 s of CPU in 30 s
#: with these against 2.6 s without (measured 2026-12-07), and the tests' clusters mostly wait.
DASK_ENV = {
    "DASK_DISTRIBUTED__WORKER__DAEMON": "False",
    "DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "1s",
    "DASK_DISTRIBUTED__ADMIN__SYSTEM_MONITOR__INTERVAL": "2s",
    "DASK_DISTRIBUTED__WORKER__MEMORY__MONITOR_INTERVAL": "1s",
    "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False",
}


@dataclass
class RealCluster:
    """A running scheduler and its workers, with their processes."""

    address: str
    scheduler: subprocess.Popen[bytes]
    workers: list[subprocess.Popen[bytes]] = field(default_factory=list)
    logs: Path | None = None
    #: How the workers were started, so a killed one can be replaced (see ``replace_worker``).
    worker_env: dict[str, str] = field(default_factory=dict)
    worker_prefix: list[str] = field(default_factory=list)
    #: The workers' working directory (``None``: this process's).
    worker_cwd: Path | None = None
    #: A folder the workers do not see (an empty tmpfs over it in their mount namespace), if any.
    hidden: Path | None = None

    def kill_worker(self, index: int = 0) -> int:
        """SIGKILL worker ``index``; return its pid."""
        proc = self.workers[index]
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        return proc.pid

    def replace_worker(self, index: int) -> None:
        """Start a fresh worker in place of worker ``index`` (killed) and wait until the scheduler
        has exactly the workers of this cluster: a shared cluster is handed out whole again after
        a test that killed a worker (one worker start rather than a cluster's)."""
        if self.workers[index].poll() is None:
            raise RuntimeError(f"worker {index} is still running")
        names = {f"w{i}" for i in range(len(self.workers))}
        # the scheduler refuses a name it still holds: the killed worker's must be gone first
        _wait_for_worker_names(self.address, names - {f"w{index}"}, time.monotonic() + 60)
        self.workers[index] = _start_worker(self, index)
        _wait_for_worker_names(self.address, names, time.monotonic() + 90)


def _dask_command() -> list[str]:
    """The ``dask`` console script of the running interpreter's environment."""
    script = Path(sys.executable).with_name("dask")
    return [str(script)] if script.exists() else [sys.executable, "-m", "dask"]


def _wait_for_workers(address: str, count: int, deadline: float) -> None:
    from distributed import Client

    with Client(address, timeout=30) as client:
        client.wait_for_workers(count, timeout=max(1.0, deadline - time.monotonic()))


def _wait_for_worker_names(address: str, names: set[str], deadline: float) -> None:
    """Wait until the scheduler's workers are exactly ``names`` (a killed one removed, its
    replacement registered)."""
    from distributed import Client

    with Client(address, timeout=30) as client:
        while {str(info["name"]) for info in client.scheduler_info()["workers"].values()} != names:
            if time.monotonic() > deadline:
                raise RuntimeError(f"the scheduler's workers did not become {sorted(names)}")
            time.sleep(0.1)


def _start_worker(cluster: RealCluster, index: int) -> subprocess.Popen[bytes]:
    """Start ``dask worker`` number ``index`` (named ``w{index}``, no nanny, one thread) for ``cluster``."""
    assert cluster.logs is not None
    wlog = open(_fresh(cluster.logs, f"worker{index}", ".log"), "wb")  # noqa: SIM115 - closed with the process
    env = {**os.environ, **DASK_ENV, **cluster.worker_env}
    return subprocess.Popen(
        [*cluster.worker_prefix, *_dask_command(), "worker", cluster.address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
         "--host", "127.0.0.1", "--name", f"w{index}", "--lifetime", LIFETIME, "--death-timeout", "60",
         "--local-directory", str(cluster.logs / f"w{index}")],
        stdout=wlog, stderr=subprocess.STDOUT, env=env, cwd=cluster.worker_cwd,
    )


def _fresh(folder: Path, stem: str, suffix: str) -> Path:
    """``folder/stem.suffix``, or ``stem-1``, ``stem-2``... when taken (a replaced worker keeps
    its predecessor's log)."""
    path, n = folder / f"{stem}{suffix}", 0
    while path.exists():
        n += 1
        path = folder / f"{stem}-{n}{suffix}"
    return path


def start_cluster(
    tmp: Path, workers: int = 2, worker_env: dict[str, str] | None = None, worker_prefix: list[str] | None = None,
    worker_cwd: Path | None = None,
) -> RealCluster:
    """Start ``dask scheduler`` and ``workers`` x ``dask worker`` on 127.0.0.1 (no nanny).

    ``worker_prefix`` goes before each worker's command (it must ``exec`` the command, so the pid
    stays the worker's): :func:`hidden_folder_prefix` gives workers their own view of the disk.
    ``worker_cwd``: the folder the workers run in (default: this process's working directory).
    """
    pytest.importorskip("distributed", reason="the cluster tests need the test extra (distributed)")
    tmp.mkdir(parents=True, exist_ok=True)
    scheduler_file = tmp / "scheduler.json"
    env = {**os.environ, **DASK_ENV}
    log = open(tmp / "scheduler.log", "wb")  # noqa: SIM115 - closed with the process
    scheduler = subprocess.Popen(
        [*_dask_command(), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(scheduler_file), "--idle-timeout", LIFETIME],
        stdout=log, stderr=subprocess.STDOUT, env=env,
    )
    deadline = time.monotonic() + 60
    while not scheduler_file.exists() or not scheduler_file.read_text().strip():
        if scheduler.poll() is not None or time.monotonic() > deadline:
            scheduler.kill()
            raise RuntimeError(f"dask scheduler did not start: {(tmp / 'scheduler.log').read_text()[-2000:]}")
        time.sleep(0.1)
    address = json.loads(scheduler_file.read_text())["address"]
    cluster = RealCluster(address, scheduler, logs=tmp, worker_env=dict(worker_env or {}), worker_prefix=list(worker_prefix or []),
                          worker_cwd=worker_cwd)
    try:
        for i in range(workers):
            cluster.workers.append(_start_worker(cluster, i))
        _wait_for_workers(address, workers, time.monotonic() + 90)
    except BaseException:
        stop_cluster(cluster)
        raise
    return cluster


def hidden_folder_prefix(folder: Path) -> list[str]:
    """A worker prefix that runs the worker in its own mount namespace with an empty tmpfs over
    ``folder``: the worker does not see what this machine writes there (as a worker on another
    machine would not see a local disk). Skips the test when this kernel refuses user namespaces."""
    prefix, refused = _hidden_folder_prefix(folder)
    if prefix is None:
        pytest.skip(f"unshare cannot make a private mount namespace here: {refused}")
    return prefix


def _hidden_folder_prefix(folder: Path) -> tuple[list[str] | None, str]:
    """(:func:`hidden_folder_prefix`'s prefix, "") or (None, why this kernel refuses it)."""
    folder.mkdir(parents=True, exist_ok=True)
    prefix = ["unshare", "--user", "--map-root-user", "--mount", "sh", "-c", 'mount -t tmpfs none "$0" && exec "$@"', str(folder)]
    check = subprocess.run([*prefix, "true"], capture_output=True, timeout=30)
    return (prefix, "") if check.returncode == 0 else (None, check.stderr.decode()[-200:])


def stop_cluster(cluster: RealCluster) -> None:
    """Stop every process of ``cluster`` by its pid: SIGTERM to all, then SIGKILL to any still
    running 1 s later (one deadline for all: a worker busy in a house can take its time to
    close, and the test has nothing left to learn from it; a worker that has run a task does not
    end on SIGTERM within 5 s with this distributed, so a longer deadline is only waited out)."""
    procs = [*cluster.workers, cluster.scheduler]
    for proc in procs:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + 1
    for proc in procs:
        try:
            proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)



#: The clusters ``shared_dask_cluster`` and ``shared_hidden_cluster`` hand out, while they run.
_shared: dict[str, RealCluster] = {}


def _stop_shared_clusters() -> None:
    while _shared:
        stop_cluster(_shared.popitem()[1])


def _shared_cluster(kind: str, start: Callable[[], RealCluster]) -> RealCluster:
    """The running shared cluster ``kind``, whole: a worker found gone (a test killed it) is
    replaced; a fresh cluster from ``start()`` when there is none yet, or its scheduler or more
    than one worker is gone."""
    cluster = _shared.get(kind)
    gone = [] if cluster is None else [i for i, proc in enumerate(cluster.workers) if proc.poll() is not None]
    if cluster is not None and cluster.scheduler.poll() is None and len(gone) <= 1:
        try:
            for index in gone:
                cluster.replace_worker(index)
            return cluster
        except RuntimeError:  # the replacement never registered: start afresh
            pass
    old = _shared.pop(kind, None)
    if old is not None:
        stop_cluster(old)
    cluster = _shared[kind] = start()
    return cluster


@pytest.fixture
def shared_dask_cluster(tmp_path_factory) -> RealCluster:
    """A scheduler and two single-threaded workers on 127.0.0.1, shared by the tests of this
    folder that run one after another, across their modules (a start costs seconds of CPU, a
    scheduler's and each worker's, and the workers load what the tests run once): a test may
    kill a worker, and the next test to ask gets a fresh one in its place (one worker's start,
    and none when no test asks again); a cluster found with its scheduler (or both workers)
    gone is started afresh. Stopped after the last of this folder's tests in a row
    (:func:`pytest_runtest_teardown`) and at the end of the session. The workers run in a folder
    of their own (``worker_cwd``), as workers on other machines do: not in this process's."""

    def start() -> RealCluster:
        tmp = tmp_path_factory.mktemp("shared-cluster")
        (tmp / "worker-cwd").mkdir()
        return start_cluster(tmp, workers=2, worker_cwd=tmp / "worker-cwd")

    return _shared_cluster("cluster", start)


@pytest.fixture
def shared_hidden_cluster(tmp_path_factory) -> RealCluster:
    """A scheduler and one worker that does not see the folder ``hidden`` (an empty tmpfs over it
    in its own mount namespace, :func:`hidden_folder_prefix`), shared like ``shared_dask_cluster``
    by the tests that write where no worker sees (each under a folder of its own in ``hidden``).
    Skips the test when this kernel refuses user namespaces."""

    def start() -> RealCluster:
        tmp = tmp_path_factory.mktemp("hidden-cluster")
        started = start_cluster(tmp, workers=1, worker_prefix=hidden_folder_prefix(tmp / "hidden"))
        started.hidden = tmp / "hidden"
        return started

    return _shared_cluster("hidden", start)


def pytest_runtest_teardown(item: pytest.Item, nextitem: pytest.Item | None) -> None:
    """Stop the shared cluster when the next test is not one of this folder's (or there is
    none): an idle cluster is not kept for a later run of them (another order, another file)."""
    if nextitem is None or Path(nextitem.path).parent != Path(__file__).parent:
        _stop_shared_clusters()


def pytest_sessionfinish(session: pytest.Session) -> None:
    _stop_shared_clusters()


@pytest.fixture(scope="session")
def cluster_release(tmp_path_factory) -> Path:
    """2 houses, 2 pairs, 4 (pair, direction)s, 3 frames: 4 instances per condition."""
    from povagent.testing.pytest_plugin import write_release

    return write_release(tmp_path_factory.mktemp("cluster-release") / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)


@pytest.fixture
def write_sweep(tmp_path, cluster_release, povagent_host, offline_plugin_file):
    """``write_sweep(output, delay_s=0, runs=1, concurrency=4, extra="") -> Path``: a sweep over the
    conditions (three cells) with the offline ``test-center`` backend."""
    import yaml

    def make(output: Path, *, delay_s: float = 0.0, runs: int = 1, concurrency: int = 4, extra: str = "", axes: str = "conditions: [a, b, c]",
             base_extra: dict | None = None) -> Path:
        base = {
            "plugins": [str(offline_plugin_file)],  # the runner tests' offline plugin, beside the YAML
            "dataset": {"path": str(cluster_release)},
            "backend": {"name": "test-center", "options": {"delay_s": delay_s}},
            "strategy": "test-point",
            "parser": "test-json",
            "runs": runs,
            "concurrency": concurrency,
            "output": "ignored-by-sweeps",
            **(base_extra or {}),
        }
        name = Path(output).name
        (tmp_path / f"{name}-base.yaml").write_text(yaml.safe_dump(base))
        path = tmp_path / f"{name}.yaml"
        path.write_text(f"base: {name}-base.yaml\noutput: {output}\naxes:\n  {axes}\n{extra}")
        return path

    return make


@pytest.fixture
def cluster_factory(tmp_path: Path) -> Iterator[Callable[..., RealCluster]]:
    """``cluster_factory(workers=1, worker_prefix=...)`` starts a custom cluster; all are stopped after the test."""
    started: list[RealCluster] = []

    def start(**options: Any) -> RealCluster:
        cluster = start_cluster(tmp_path / f"cluster{len(started)}", **options)
        started.append(cluster)
        return cluster

    try:
        yield start
    finally:
        for cluster in started:
            stop_cluster(cluster)


@pytest.fixture
def spare_cluster(cluster_factory: Callable[..., RealCluster]) -> Iterator[RealCluster]:
    """A one-worker cluster that this test may break (kill its scheduler), stopped after it: the
    running ``shared_hidden_cluster`` when there is one, taken over (the next test to ask for
    that starts a fresh one), else a fresh one. The hidden cluster's worker sees every folder but
    its ``hidden`` one, which these tests do not use, and has already loaded what the hidden
    tests ran (the house pipeline): a scheduler's and a worker's start saved, and their imports."""
    hidden = _shared.get("hidden")
    if hidden is None or any(proc.poll() is not None for proc in (hidden.scheduler, *hidden.workers)):
        yield cluster_factory(workers=1)
        return
    del _shared["hidden"]
    try:
        yield hidden
    finally:
        stop_cluster(hidden)

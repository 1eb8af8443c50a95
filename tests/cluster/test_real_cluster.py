"""The real-cluster fixture itself: tasks run on worker processes, and a killed worker is gone."""

from __future__ import annotations

import os

from povagent.cluster.client import cluster_client


def test_tasks_run_in_the_worker_processes_not_here(dask_cluster) -> None:
    with cluster_client(dask_cluster.address) as client:
        assert client is not None
        pids = set(client.gather(client.map(lambda i: os.getpid(), range(8), pure=False)))
    assert os.getpid() not in pids
    assert pids <= {w.pid for w in dask_cluster.workers}


def test_a_killed_worker_leaves_the_other_to_finish(dask_cluster) -> None:
    killed = dask_cluster.kill_worker(0)
    with cluster_client(dask_cluster.address) as client:
        assert client is not None
        pids = set(client.gather(client.map(lambda i: os.getpid(), range(4), pure=False)))
    assert killed not in pids
    assert pids == {dask_cluster.workers[1].pid}

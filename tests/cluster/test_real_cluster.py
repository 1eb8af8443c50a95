"""The real-cluster fixture itself: tasks run on worker processes, a killed worker is gone, and a
shared cluster gets a killed worker back."""

from __future__ import annotations

import os

from povagent.cluster.client import cluster_client


def test_tasks_run_in_the_worker_processes_not_here(shared_dask_cluster) -> None:
    dask_cluster = shared_dask_cluster
    with cluster_client(dask_cluster.address) as client:
        assert client is not None
        pids = set(client.gather(client.map(lambda i: os.getpid(), range(8), pure=False)))
    assert os.getpid() not in pids
    assert pids <= {w.pid for w in dask_cluster.workers}


def test_a_killed_worker_leaves_the_other_to_finish(shared_dask_cluster) -> None:
    dask_cluster = shared_dask_cluster
    killed = dask_cluster.kill_worker(0)
    try:
        with cluster_client(dask_cluster.address) as client:
            assert client is not None
            pids = set(client.gather(client.map(lambda i: os.getpid(), range(4), pure=False)))
    finally:  # the shared cluster gets its first worker back
        dask_cluster.replace_worker(0)
    assert killed not in pids
    assert pids == {dask_cluster.workers[1].pid}
    # replace_worker made the cluster whole again: a fresh process in the killed one's place
    assert dask_cluster.workers[0].poll() is None and dask_cluster.workers[0].pid != killed

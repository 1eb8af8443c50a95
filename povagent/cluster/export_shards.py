"""Training-export shards as cluster tasks: each shard one task, after a storage probe.

A shard is a plain function of the dataset, the plan and the options, so a worker writes the
same bytes the client would. The paths sent are absolute (a relative ``--out`` would land under
each worker's own working folder), and before any task runs every worker must read and write
the export folder as this machine sees it and see the dataset: a worker that cannot would
report its shards written where nobody reads them. What the workers say they wrote is not the
end of it either: the exporter counts the shards on disk afterwards.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from povagent.cluster.client import cluster_client
from povagent.cluster.storage import probe_storage
from povagent.errors import ClusterError


def check_export_storage(client: Any, out: Path, dataset: Path) -> None:
    """Refuse (:class:`ClusterError`, one line) unless every worker reads and writes ``out`` and
    sees ``dataset`` at the same paths."""
    found = probe_storage(client, out, [dataset])
    if not found.shared:
        cannot = found.blind + found.read_only
        raise ClusterError(
            f"{out}: worker(s) {', '.join(cannot) or '(none answered)'} cannot "
            f"{'read' if found.blind else 'write'} this folder as this machine sees it; an export on a cluster "
            "needs --out on storage every worker sees (NFS, Lustre, a shared volume) at the same path"
        )
    if found.missing:
        raise ClusterError(f"dataset folder not found on worker {found.missing[0]}; every worker must see the dataset at the same path")


def write_shards_on_cluster(
    cluster: Any,
    write: Callable[[str, str, Any, Any], int],
    dataset: Path,
    out: Path,
    shards: Sequence[Any],
    options: Any,
    on_done: Callable[[Any], None],
) -> None:
    """Run ``write(dataset, out, shard, options)`` for every shard on ``cluster`` (a
    ``--cluster`` value or a ``distributed.Client``); ``on_done(shard)`` as each one ends."""
    dataset, out = dataset.absolute(), out.absolute()
    with cluster_client(cluster) as client:
        if client is None:
            raise ClusterError("write_shards_on_cluster needs a cluster")
        check_export_storage(client, out, dataset)
        n = len(shards)
        futures = client.map(write, [str(dataset)] * n, [str(out)] * n, list(shards), [options] * n, pure=False, retries=2)
        for shard, future in zip(shards, futures):
            future.result()
            on_done(shard)

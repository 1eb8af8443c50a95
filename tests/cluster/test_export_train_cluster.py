"""export-train on a real Dask cluster writes the same bytes as one process."""

from __future__ import annotations

import hashlib
from pathlib import Path

from povagent.train.export import export_training_set
from povagent.train.export_options import ExportOptions


def _files(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_shards_written_as_cluster_tasks_equal_a_local_export(dask_cluster, generated_release: Path, tmp_path: Path) -> None:
    options = ExportOptions(format="hf", conditions=("c",), max_shard_bytes=2**20)
    local = export_training_set(generated_release, tmp_path / "local", options, check_release=False)
    remote = export_training_set(generated_release, tmp_path / "remote", options, check_release=False, cluster=dask_cluster.address)
    assert len(local.shards) > 2 and remote.shards == local.shards
    assert _files(tmp_path / "remote") == _files(tmp_path / "local")

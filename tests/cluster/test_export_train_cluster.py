"""export-train on a real Dask cluster writes the same bytes as one process."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from povagent.train.export_options import ExportOptions
from povagent.train.training_export import export_training_set


def _files(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_shards_written_as_cluster_tasks_equal_a_local_export(shared_dask_cluster, generated_release: Path, tmp_path: Path) -> None:
    dask_cluster = shared_dask_cluster
    options = ExportOptions(format="hf", conditions=("c",), max_shard_bytes=2**20)
    local = export_training_set(generated_release, tmp_path / "local", options, check_release=False)
    remote = export_training_set(generated_release, tmp_path / "remote", options, check_release=False, cluster=dask_cluster.address)
    assert len(local.shards) > 2 and remote.shards == local.shards
    assert _files(tmp_path / "remote") == _files(tmp_path / "local")


def test_a_relative_out_lands_where_the_user_ran_the_command_not_under_a_workers_folder(
    shared_dask_cluster, generated_release: Path, tmp_path: Path, monkeypatch
) -> None:
    elsewhere = shared_dask_cluster.worker_cwd  # the folder the workers run in
    assert elsewhere is not None
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    report = export_training_set(
        generated_release, Path("rel-out"), ExportOptions(format="hf", conditions=("c",)), check_release=False, cluster=shared_dask_cluster.address
    )
    assert report.shards_written == len(report.shards) > 0
    assert sorted(p.name for p in (here / "rel-out" / "data").glob("*.parquet")) == sorted(report.shards)
    assert not (elsewhere / "rel-out").exists()


def test_workers_that_cannot_see_the_out_folder_are_named_before_any_shard_is_sent(
    shared_hidden_cluster, generated_release: Path, tmp_path: Path
) -> None:
    from povagent.errors import ClusterError

    assert shared_hidden_cluster.hidden is not None
    out = shared_hidden_cluster.hidden / tmp_path.name / "out"  # where this process writes and the worker sees nothing
    with pytest.raises(ClusterError, match=f"{out}: worker\\(s\\) .* cannot read this folder"):
        export_training_set(
            generated_release, out, ExportOptions(format="hf", conditions=("c",)), check_release=False, cluster=shared_hidden_cluster.address
        )
    assert not list(out.rglob("*.parquet"))

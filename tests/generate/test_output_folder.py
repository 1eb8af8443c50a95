"""The generator writes only into an empty folder or over a dataset it wrote itself."""

from __future__ import annotations

import pytest

from povagent.errors import DatasetError
from povagent.generate import generate_dataset


def test_a_folder_holding_other_files_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(DatasetError, match="not empty"):
        generate_dataset(tmp_path, houses=1, seed=0, frames=1, progress=False)
    assert (tmp_path / "notes.txt").read_text() == "mine"


@pytest.fixture
def read_only_folder(tmp_path):
    """``tmp_path/ro``: an empty read-only tmpfs (unmounted after the test)."""
    import subprocess

    folder = tmp_path / "ro"
    folder.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(folder)], capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"mounting a tmpfs is not permitted here ({mounted.stderr.strip()})")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=True)


@pytest.mark.parametrize("cluster", [None, "local:1"])
def test_an_out_on_a_read_only_file_system_is_one_line(read_only_folder, cluster):
    if cluster is not None:
        pytest.importorskip("distributed", reason="--cluster needs the cluster extra")
    from povagent.errors import GenerationError

    out = read_only_folder / "data"
    with pytest.raises(GenerationError) as info:
        generate_dataset(out, houses=1, seed=0, frames=1, jobs=1, progress=False, cluster=cluster)
    message = str(info.value)
    assert "\n" not in message and "Read-only file system" in message and str(out) in message, message

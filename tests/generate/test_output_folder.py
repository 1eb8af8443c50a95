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

"""One loader choice for every command: a real-world set by its ``realworld.json``, any other
folder (a release, a generated set) by the release loader."""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.dataset.evaluation_set import open_evaluation_set
from povagent.dataset.loader import Dataset
from povagent.dataset.realworld import RealWorldDataset
from povagent.errors import DatasetError

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


def test_a_folder_holding_realworld_json_opens_as_a_real_world_set():
    assert isinstance(open_evaluation_set(DEMO), RealWorldDataset)


def test_a_release_layout_folder_opens_with_the_release_loader(mini_root):
    assert isinstance(open_evaluation_set(mini_root, check_images=False), Dataset)


def test_strict_reaches_the_release_loader(mini_root):
    with pytest.raises(DatasetError, match="--strict"):
        open_evaluation_set(mini_root, strict=True)

"""A dataset file that is a named pipe is a problem named by its file, found at once, never waited
on; the other houses load. (A link leading out of the dataset, to ``/dev/zero`` say, is refused
before it is opened: tests/dataset/test_files_stay_inside_dataset.py.)"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Callable

import pytest

from povagent.dataset.loader import load_dataset
from povagent.dataset.validate import validate_dataset

pytestmark = pytest.mark.timeout(60)

HOUSE = "train_house_00001"


def _house_file_a_fifo(root: Path) -> str:
    path = root / "artifacts" / HOUSE / f"{HOUSE}.json"
    path.unlink()
    os.mkfifo(path)
    return f"{HOUSE}.json"


def _exploration_log_a_fifo(root: Path) -> str:
    path = root / "artifacts" / HOUSE / "exploration_log.json"
    path.unlink()
    os.mkfifo(path)
    return "exploration_log.json"


def _frame_a_fifo(root: Path) -> str:
    path = root / "artifacts" / HOUSE / "exploration_images" / "frame_000.png"
    path.unlink()
    os.mkfifo(path)
    return "frame_000.png"


ATTACKS: dict[str, Callable[[Path], str]] = {
    "house file a FIFO": _house_file_a_fifo,
    "exploration log a FIFO": _exploration_log_a_fifo,
    "frame a FIFO": _frame_a_fifo,
}


@pytest.mark.parametrize("attack", list(ATTACKS))
def test_validate_names_a_pipe_at_once(dataset_copy, attack):
    named = ATTACKS[attack](dataset_copy)
    started = time.monotonic()
    problems = validate_dataset(dataset_copy)
    assert time.monotonic() - started < 20
    hits = [str(p) for p in problems if named in str(p)]
    assert hits and all("not a regular file" in h for h in hits), [str(p) for p in problems]


@pytest.mark.parametrize("attack", list(ATTACKS))
def test_loading_drops_the_house_and_keeps_the_other(dataset_copy, attack):
    ATTACKS[attack](dataset_copy)
    dataset = load_dataset(dataset_copy)
    assert HOUSE not in dataset.houses and "train_house_00000" in dataset.houses
    assert any("not a regular file" in str(p) for p in dataset.problems)

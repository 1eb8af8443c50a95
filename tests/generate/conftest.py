"""Fixtures for the generator's tests: small generated datasets, each made once per session (real files)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from povagent.generate import generate_dataset
from povagent.generate.house_pipeline import BuiltHouse, build_house

SEED = 7
FRAMES = 6


@dataclass
class TinyDataset:
    """A one-house dataset generated with depth maps and instance masks, and its house model."""

    root: Path
    built: BuiltHouse

    @property
    def house_dir(self) -> Path:
        return self.root / "artifacts" / self.built.house.house_id

    def pairs(self) -> list[dict]:
        return json.loads((self.house_dir / f"{self.built.house.house_id}.json").read_text())

    def log(self) -> list[dict]:
        return json.loads((self.house_dir / "exploration_log.json").read_text())

    def depth(self, stem: str) -> np.ndarray:
        return np.load(self.house_dir / "_render" / f"{stem}.depth.npy").astype(np.float32)

    def instance(self, stem: str) -> np.ndarray:
        return np.array(Image.open(self.house_dir / "_render" / f"{stem}.instance.png"))


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory: pytest.TempPathFactory) -> TinyDataset:
    """One house, six exploration frames, written with ``with_render=True``."""
    from shared_sets import made_once

    # the generator's test files run in several xdist workers: the set is made once between them
    def make(root: Path) -> None:
        generate_dataset(root, houses=1, seed=SEED, frames=FRAMES, jobs=1, progress=False, with_render=True)

    root = made_once(tmp_path_factory, "tiny-generated", make)
    return TinyDataset(root, build_house(SEED, 0))


@dataclass
class CommandOutput:
    """A dataset ``povagent generate`` wrote, and what the command printed."""

    root: Path
    output: str


@pytest.fixture(scope="session")
def two_houses(tmp_path_factory: pytest.TempPathFactory) -> CommandOutput:
    """Two houses (seed 5, two exploration frames: its ``meta.json`` says so) written by the
    ``generate`` command in this process (``--jobs 1``): the command's own test reads it, the
    determinism tests compare a worker pool's bytes with it, and the resume tests copy its
    finished houses. Read only: tests that change it copy it.

    Those test files run in several xdist workers: the set is made once between them, and what
    the command printed is kept beside it (``command-output.txt``) for the workers that read it."""
    from shared_sets import made_once
    from typer.testing import CliRunner

    from povagent.cli import app

    def make(root: Path) -> None:
        args = ["generate", "--out", str(root), "--houses", "2", "--seed", "5", "--frames", "2", "--jobs", "1"]
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 0, result.output
        (root.parent / "command-output.txt").write_text(result.output)

    root = made_once(tmp_path_factory, "two-houses", make)
    return CommandOutput(root, (root.parent / "command-output.txt").read_text())

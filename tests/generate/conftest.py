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

"""Fixtures for the generator's tests: small generated datasets, each made once per session (real files)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from povagent.generate import generate_dataset, house_pipeline
from povagent.generate.house_pipeline import BuiltHouse, build_house
from povagent.generate.record import house_id

SEED = 7
FRAMES = 6


@dataclass
class TinyDataset:
    """A one-house dataset generated with depth maps and instance masks, and its house model."""

    root: Path
    #: the house the generation built, where this process made the set (else built on first use)
    made_here: BuiltHouse | None = None

    @cached_property
    def built(self) -> BuiltHouse:
        return self.made_here if self.made_here is not None else build_house(SEED, 0)

    @property
    def house_dir(self) -> Path:
        return self.root / "artifacts" / house_id(0)  # (the tests that only read files build no house)

    def pairs(self) -> list[dict]:
        return json.loads((self.house_dir / f"{house_id(0)}.json").read_text())

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

    # the generator's test files run in several xdist workers: the set is made once between them.
    # The process that makes it keeps the house the generation built (a second build is a third
    # of a second); the others build it when a test first asks for it
    kept: list[BuiltHouse] = []

    def build_and_keep(seed: int, index: int, shadows: bool = True) -> BuiltHouse:
        kept.append(build_house(seed, index, shadows))
        return kept[-1]

    def make(root: Path) -> None:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(house_pipeline, "build_house", build_and_keep)
            generate_dataset(root, houses=1, seed=SEED, frames=FRAMES, jobs=1, progress=False, with_render=True)

    root = made_once(tmp_path_factory, "tiny-generated", make)
    (made_here,) = kept or [None]
    return TinyDataset(root, made_here)

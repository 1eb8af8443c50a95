"""Fixtures for the active mode: the session's generated set (two houses), its instances, a
rebuilt house, and an episode builder with a plain render function."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from povagent.active.floor import Floor
from povagent.active.house import house_for
from povagent.active.live_episode import Episode
from povagent.active.pose import Pose
from povagent.active.speaker import PairFacts
from povagent.plugins import get_plugin_host


@pytest.fixture(scope="session")
def active_dataset(generated_release: Path) -> Path:
    """The generated set every active test shares (made once a session)."""
    return generated_release


@pytest.fixture(scope="session")
def house0(active_dataset):
    """House 0, rebuilt."""
    return house_for(active_dataset, "train_house_00000")


@pytest.fixture(scope="session")
def floor0(house0) -> Floor:
    """House 0's floor."""
    return Floor(house0.built.house)


def pose_sha(pose: Pose) -> str:
    """A stand-in view hash: distinct per pose (the episode only numbers and records it)."""
    return hashlib.sha256(repr(pose).encode()).hexdigest()


FACTS = PairFacts("I was sitting on the sofa reading when I saw the mug left of the lamp.", "Sofa", "FloorLamp")


@pytest.fixture
def facts() -> PairFacts:
    """A speaker's facts: the Stated sentence, a sofa, facing a floor lamp."""
    return FACTS


@pytest.fixture
def make_episode(floor0):
    """``make_episode(budget=8, frames=3, clock=None) -> Episode`` on house 0's floor."""

    def make(budget: int = 8, frames: int = 3, **kwargs) -> Episode:
        poses = [Pose(1.0 + k, 0.9, -2.0, 30.0 * k, 30.0) for k in range(frames)]
        return Episode(poses, poses[0], pose_sha, lambda: floor0, FACTS, get_plugin_host().tools(), budget, **kwargs)

    return make

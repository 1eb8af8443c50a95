"""Same seed, same bytes: whatever the number of worker processes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from povagent.generate import generate_dataset


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def two_runs(two_houses, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, bytes], dict[str, bytes]]:
    """The session's two houses made in this process (by the ``generate`` command), and the same
    two made by a pool of two worker processes (one house each)."""
    meta = json.loads((two_houses.root / "meta.json").read_text())
    b = tmp_path_factory.mktemp("run_b")
    generate_dataset(b, houses=2, seed=meta["seed"], frames=meta["generator"]["frames"], jobs=2, progress=False)
    return _tree(two_houses.root), _tree(b)


def test_two_runs_with_the_same_seed_write_the_same_file_names(two_runs):
    a, b = two_runs
    assert sorted(a) == sorted(b)
    assert "meta.json" in a and any(name.endswith("train_house_00001.json") for name in a)


def test_two_runs_with_the_same_seed_write_identical_bytes_even_with_other_job_counts(two_runs):
    a, b = two_runs
    differing = [name for name in a if a[name] != b.get(name)]
    assert differing == []


def test_a_different_seed_gives_a_different_house(tmp_path: Path, two_houses, two_runs):
    # the same options but the seed (the frame count alone can change the first frame)
    a, _ = two_runs
    meta = json.loads((two_houses.root / "meta.json").read_text())
    generate_dataset(tmp_path, houses=1, seed=meta["seed"] + 1, frames=meta["generator"]["frames"], jobs=1, progress=False)
    name = "artifacts/train_house_00000/exploration_images/frame_000.png"
    assert (tmp_path / name).read_bytes() != a[name]

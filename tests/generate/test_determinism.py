"""Same seed, same bytes: whatever the number of worker processes."""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.generate import generate_dataset


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, bytes], dict[str, bytes]]:
    a, b = tmp_path_factory.mktemp("run_a"), tmp_path_factory.mktemp("run_b")
    generate_dataset(a, houses=2, seed=11, frames=2, jobs=1, progress=False)
    generate_dataset(b, houses=2, seed=11, frames=2, jobs=2, progress=False)
    return _tree(a), _tree(b)


def test_two_runs_with_the_same_seed_write_the_same_file_names(two_runs):
    a, b = two_runs
    assert sorted(a) == sorted(b)
    assert "meta.json" in a and any(name.endswith("train_house_00001.json") for name in a)


def test_two_runs_with_the_same_seed_write_identical_bytes_even_with_other_job_counts(two_runs):
    a, b = two_runs
    differing = [name for name in a if a[name] != b.get(name)]
    assert differing == []


def test_a_different_seed_gives_a_different_house(tmp_path: Path, two_runs):
    a, _ = two_runs
    generate_dataset(tmp_path, houses=1, seed=12, frames=1, jobs=1, progress=False)
    name = "artifacts/train_house_00000/exploration_images/frame_000.png"
    assert (tmp_path / name).read_bytes() != a[name]

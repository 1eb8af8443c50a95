"""Which faces form one plane: the sorted search finds exactly the pairs a comparison of every
pair with every other finds."""

from __future__ import annotations

import numpy as np

from povagent.generate.face_groups import PARALLEL_TOLERANCE, PLANE_TOLERANCE, coplanar_touching_pairs


def every_pair(normal, offset, lo, hi) -> set[tuple[int, int]]:
    found = set()
    for i in range(len(normal)):
        for j in range(len(normal)):
            if i == j or not ((lo[i] <= hi[j]).all() and (lo[j] <= hi[i]).all()):
                continue
            cos = float(normal[i] @ normal[j])
            same = cos >= 1 - PARALLEL_TOLERANCE and abs(offset[i] - offset[j]) <= PLANE_TOLERANCE
            opposite = cos <= -(1 - PARALLEL_TOLERANCE) and abs(offset[i] + offset[j]) <= PLANE_TOLERANCE
            if same or opposite:
                found.add((i, j))
    return found


def test_the_sorted_search_finds_every_coplanar_touching_pair_and_no_other():
    rng = np.random.default_rng(5)
    n = 300
    axes = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, 0.8, 0]])
    normal = axes[rng.integers(0, 4, n)] * rng.choice([-1.0, 1.0], n)[:, None]
    # offsets on a few planes, some a hair apart (inside and outside the tolerance), either sign
    offset = rng.choice([0.0, 1.0, 2.5], n) + rng.choice([0.0, 0.4, 0.9, 1.1, 3.0], n) * PLANE_TOLERANCE
    offset *= rng.choice([-1.0, 1.0], n)
    lo = rng.random((n, 3)) * 4
    hi = lo + rng.random((n, 3)) * 1.5
    left, right = coplanar_touching_pairs(normal, offset, lo, hi)
    found = set(zip(left.tolist(), right.tolist()))
    assert len(found) == len(left)  # no pair twice
    assert found == every_pair(normal, offset, lo, hi)
    assert found  # the case is not empty

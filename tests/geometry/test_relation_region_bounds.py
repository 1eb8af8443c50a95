"""One instance's relation region costs bounded time and memory whatever size its anchor has,
(``validate``'s side of it: tests/dataset/test_object_box_bounds.py).

The region's samples once grew with the square of the anchor's size (a 300 m anchor: 5 s and
1.3 GB for one instance; 1,500 m: MemoryError), from a dataset that passed ``validate``.
"""

from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pytest

from povagent.geometry.ground_truth import AnchorBox, PlacementCase
from povagent.geometry.relation_region import DISTANCE_STEP, MAX_STEPS, valid_placements


def huge_case(direction: str, side_m: float, anchor_type: str = "Sofa", surface: str = "on the floor") -> PlacementCase:
    box = AnchorBox(center_xz=(0.0, 0.0), half_xz=(side_m / 2, side_m / 2), top=1.0)
    return PlacementCase(direction, box, anchor_type, (0.0, 0.5, 0.0), (0.0, 0.5, 0.0), (-side_m, 1.5, 0.0), "appropriate", surface, (9.0, 9.0, 9.0))


@pytest.mark.parametrize("side_m", [300.0, 1500.0, 1e9])
def test_up_samples_over_a_huge_top_stay_bounded_in_count_time_and_memory(side_m):
    tracemalloc.start()
    t0 = time.process_time()
    try:
        points = valid_placements(huge_case("up", side_m))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(points) <= (MAX_STEPS + 1) ** 2 + 1
    assert time.process_time() - t0 < 1.0
    assert peak < 50e6
    # the top is still covered edge to edge, only coarser
    assert points[:, 0].min() == pytest.approx(-side_m / 2) and points[:, 0].max() == pytest.approx(side_m / 2)


def test_samples_on_a_huge_flat_top_stay_bounded():
    points = valid_placements(huge_case("left", 1500.0, anchor_type="Bed", surface="on the bed"))
    assert len(points) <= 1 + 19 * (MAX_STEPS + 1)  # 19 sector directions


def test_an_ordinary_anchor_keeps_the_fine_spacing():
    points = valid_placements(huge_case("up", 2.0))
    xs = np.unique(np.round(points[1:, 0], 9))
    assert np.max(np.diff(xs)) <= DISTANCE_STEP + 1e-9

"""Every ground-truth point is a place a target can be: inside the house, outside walls."""

from __future__ import annotations

import numpy as np

from povagent.dataset.loader import ground_truth_point, load_dataset
from povagent.dataset.release_models import PairEntry


def test_every_ground_truth_point_lies_inside_the_house(tiny_dataset):
    plan = tiny_dataset.built.house.plan
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        for d in entry.valid_directions():
            assert plan.inside_house(ground_truth_point(entry, d)), (entry.pair_id, d)


def test_no_ground_truth_point_lies_in_a_wall(tiny_dataset):
    plan = tiny_dataset.built.house.plan
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        for d in entry.valid_directions():
            assert not plan.point_in_wall(ground_truth_point(entry, d)), (entry.pair_id, d)


def test_raw_placements_agree_with_the_surface_corrected_ground_truth(tiny_dataset):
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        for d in entry.valid_directions():
            raw = np.array(entry.placements[d].position.as_tuple())
            assert np.allclose(raw, ground_truth_point(entry, d), atol=1e-3)


def test_floor_targets_stand_on_the_floor(tiny_dataset):
    dataset = load_dataset(tiny_dataset.root)
    for house in dataset.houses.values():
        for pair in house.pairs.values():
            for d in pair.valid_directions():
                if "floor" in (pair.stage3[d].surface or ""):
                    assert abs(ground_truth_point(pair, d)[1] - 0.2) < 1e-6

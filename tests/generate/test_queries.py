"""Sentences, targets and the pluggable surface judge."""

from __future__ import annotations

import re

import numpy as np

from povagent.dataset.models import PairEntry
from povagent.generate import JudgeRequest, PhysicalRulesJudge, SurfaceJudge, SurfaceVerdict
from povagent.generate.exploration import plan_tour
from povagent.generate.pairs import build_pairs
from povagent.generate.sentences import OBJECT_NAMES, TARGET_POOLS


def _mentions(sentence: str, object_type: str) -> bool:
    text = sentence.lower()
    return any(re.search(rf"\b{re.escape(n.lower())}\b", text) for n in OBJECT_NAMES[object_type])


def test_stated_sentences_name_the_observer_object_and_inferred_ones_do_not(tiny_dataset):
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        observer = entry.object_observer.raw_metadata.objectType
        for d in entry.valid_directions():
            assert _mentions(entry.stage5[d].type_b, observer)
            before_sighting = re.split(r"\b(saw|spotted|noticed)\b", entry.stage5[d].type_a)[0]
            assert not _mentions(before_sighting, observer), entry.stage5[d].type_a


def test_given_sentences_state_only_the_relation_to_the_anchor(tiny_dataset):
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        anchor = entry.landmark_type
        for d in entry.valid_directions():
            c = entry.stage6[d].type_c
            assert c.startswith("The ") and _mentions(c, anchor)
            assert " I " not in c


def test_targets_come_from_the_pool_of_their_surface(tiny_dataset):
    for entry in tiny_dataset.pairs():
        for d, placement in entry["placements"].items():
            pool = TARGET_POOLS[placement["surface_pool"]]
            assert placement["object_type"] in pool
            if "floor" in entry["stage3"][d]["surface"]:
                assert placement["surface_pool"] == "Floor"


class FrontAndUpJudge:
    """A throwaway judge: only front (on the floor) and up (on the anchor); stands in for a VLM."""

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        assert request.image is not None and request.image.shape == (512, 512, 3)
        if request.direction == "front":
            return SurfaceVerdict("appropriate", "on the floor")
        if request.direction == "up":
            return SurfaceVerdict("appropriate", "on the anchor")
        return SurfaceVerdict("inappropriate", None)


def test_a_plugged_in_judge_decides_which_directions_exist(tiny_dataset):
    assert isinstance(FrontAndUpJudge(), SurfaceJudge) and isinstance(PhysicalRulesJudge(), SurfaceJudge)
    house, renderer = tiny_dataset.built.house, tiny_dataset.built.renderer
    counts = [renderer.render(c).pixel_counts() for c in plan_tour(house, renderer, 4)]
    pairs = build_pairs(house, renderer, counts, FrontAndUpJudge(), np.random.default_rng(0), max_pairs=2)
    assert pairs
    assert all([q.direction for q in p.queries] == ["front", "up"] for p in pairs)

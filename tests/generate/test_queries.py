"""Sentences, targets and the pluggable surface judge."""

from __future__ import annotations

import re

import numpy as np

from povagent.dataset.release_models import PairEntry
from povagent.generate import JudgeRequest, PhysicalRulesJudge, SurfaceJudge, SurfaceVerdict
from povagent.generate.exploration import plan_tour
from povagent.generate.pairs import build_pairs
from povagent.generate.sentences import ENTRANCE_NAMES, OBJECT_NAMES, TARGET_POOLS


def _mentions(sentence: str, object_type: str) -> bool:
    text = sentence.lower()
    names = OBJECT_NAMES[object_type] + (ENTRANCE_NAMES if object_type == "Doorway" else ())
    return any(re.search(rf"\b{re.escape(n.lower())}\b", text) for n in names)


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


def test_a_plugged_in_judge_decides_the_directions_of_a_generated_dataset(tmp_path):
    import json

    from povagent.generate import generate_dataset

    generate_dataset(tmp_path, houses=1, seed=7, frames=3, progress=False, judge=FrontAndUpJudge())
    entries = json.loads((tmp_path / "artifacts/train_house_00000/train_house_00000.json").read_text())
    assert entries and all(set(e["placements"]) <= {"front", "up"} for e in entries)
    assert json.loads((tmp_path / "meta.json").read_text())["generator"]["judge"] == "FrontAndUpJudge"


def test_doorways_are_named_by_the_rooms_they_join_or_as_the_front_door(tiny_dataset):
    from povagent.generate.sentences import ROOM_WORDS, anchor_phrase

    house = tiny_dataset.built.house
    rng = np.random.default_rng(0)
    names = []
    for doorway in (o for o in house.objects if o.object_type == "Doorway"):
        name = anchor_phrase(house, doorway, rng)
        if "entrance" in doorway.flags:
            assert name in ENTRANCE_NAMES
            continue
        opening = next(
            o for o in house.plan.openings
            if not o.is_entrance and abs(o.center[0] - doorway.center[0]) + abs(o.center[1] - doorway.center[2]) < 1e-3
        )
        if name is None:  # another doorway joins the same two kinds of room
            continue
        for room in opening.rooms:
            assert ROOM_WORDS[house.plan.rooms[room].room_type] in name
        names.append(frozenset(ROOM_WORDS[house.plan.rooms[r].room_type] for r in opening.rooms))
    assert names and len(names) == len(set(names))


def test_anchors_are_named_with_natural_variants_of_their_type(tiny_dataset):
    from povagent.generate.sentences import anchor_phrase

    house = tiny_dataset.built.house
    sofa = next(o for o in house.objects if o.object_type == "Sofa")
    names = {anchor_phrase(house, sofa, np.random.default_rng(seed)) for seed in range(20)}
    assert {"sofa", "couch"} <= {n.split(" in the ")[0] for n in names if n}


def test_inferred_sentences_include_the_papers_own_form(tiny_dataset):
    # "While replacing the bulb, I spotted the book to the left of the bed."
    from povagent.generate.sentences import sentences

    house = tiny_dataset.built.house
    observer = house.objects[0]
    forms = {
        sentences(observer, "Sofa", "sofa", "left", "Book", False, house, np.random.default_rng(seed))[0]
        for seed in range(40)
    }
    paper_form = r"While [a-z]+ing\b[^,]*, I (saw|spotted|noticed) the book to the left of the sofa\.$"
    assert any(re.match(paper_form, a) for a in forms)


def test_a_target_on_top_of_an_anchor_comes_from_that_anchors_pool(tiny_dataset):
    from povagent.generate.judge import UP_SURFACES, surface_noun
    from povagent.generate.scene import PlacedObject
    from povagent.generate.sentences import target_pool

    for object_type in sorted(UP_SURFACES):
        anchor = PlacedObject("a", object_type, "x", (0.0, 0.5, 0.0), (1.0, 1.0, 1.0), 0, 0)
        pool, _ = target_pool(f"on the {surface_noun(object_type)}", anchor, tiny_dataset.built.house)
        assert pool == object_type  # never the floor pool: no dumbbell on top of a bookshelf

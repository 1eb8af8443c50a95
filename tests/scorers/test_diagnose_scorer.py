"""The ``diagnose`` and ``relation`` scorers on hand-placed answers over a generated set."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.answers.spec import ParsedAnswer, ParseStatus, unparseable
from povagent.dataset.loader import load_dataset, placement_case
from povagent.dataset.realworld_set import load_realworld
from povagent.errors import ConfigError
from povagent.geometry.counterfactual import egocentric_target, mirrored_target
from povagent.scoring.diagnosis import ANCHOR_THRESHOLD, BIAS_MARGIN, official_uv
from povagent_plugins.scorers.diagnose import DiagnoseScorer
from povagent_plugins.scorers.relation_scorer import RelationScorer


@pytest.fixture(scope="module")
def generated(generated_release):
    return load_dataset(generated_release, check_images=False)


def answer(frame: int | None, u: float, v: float) -> ParsedAnswer:
    return ParsedAnswer(status=ParseStatus.OK, selected_image=frame, x=u * 512, y=v * 512)


def anchor_frames(inst, shows: bool = True):
    anchor = str(inst.anchor_object.objectId)
    return [f for f in inst.frames if (anchor in f.in_frame_hits) == shows]


def case_of(generated, inst):
    return placement_case(generated.houses[inst.house_id].pairs[inst.pair_id], inst.direction)


def test_the_ground_truth_in_a_frame_showing_the_anchor_is_correct(generated):
    scorer, relation = DiagnoseScorer(), RelationScorer()
    checked = 0
    for inst in generated.instances(conditions=["a", "c"]):
        for frame in anchor_frames(inst) if inst.condition == "a" else inst.frames:
            if not frame.camera.project(np.asarray(inst.target)).in_frame:
                continue
            u, v = official_uv(np.asarray(inst.target), frame)
            scores = scorer.score(inst, answer(frame.index, u, v), generated)
            assert scores["step"] == "correct", (inst.id, frame.index, scores)
            assert relation.score(inst, answer(frame.index, u, v), generated)["success"]
            checked += 1
    assert checked > 100


def test_a_frame_without_the_anchor_fails_at_the_frame_step(generated):
    inst = next(i for i in generated.instances(conditions=["b"]) if anchor_frames(i, shows=False))
    frame = anchor_frames(inst, shows=False)[0]
    u, v = official_uv(np.asarray(inst.target), frame)
    scores = DiagnoseScorer().score(inst, answer(frame.index, u, v), generated)
    assert scores["step"] == "frame" and scores["frame_shows"] in ("observer", "neither")


def test_a_point_far_from_the_anchor_fails_at_the_anchor_step(generated):
    found = 0
    for inst in generated.instances(conditions=["a"]):
        for frame in anchor_frames(inst):
            scores = [DiagnoseScorer().score(inst, answer(frame.index, u, v), generated) for u, v in ((0, 0), (1, 0), (0, 1), (1, 1))]
            far = max(scores, key=lambda s: s["anchor_distance"])
            if far["anchor_distance"] > ANCHOR_THRESHOLD:
                assert far["step"] == "anchor"
                found += 1
    assert found > 20


def test_the_egocentric_and_mirrored_targets_fail_at_the_viewpoint_step(generated):
    ego_seen = mirror_seen = 0
    for inst in generated.instances(conditions=["a"], directions=["left", "right", "front"]):
        case = case_of(generated, inst)
        for frame in anchor_frames(inst):
            truth = official_uv(np.asarray(inst.target), frame)
            for target, kind in ((egocentric_target(case, frame.camera), "ego"), (mirrored_target(case), "mirror")):
                uv = official_uv(target, frame)
                if math.dist(uv, truth) <= BIAS_MARGIN:
                    continue
                scores = DiagnoseScorer().score(inst, answer(frame.index, *uv), generated)
                if scores["anchor_distance"] > ANCHOR_THRESHOLD:
                    continue  # a counterfactual off the image edge: the anchor step comes first
                assert scores["step"] == "viewpoint", (inst.id, frame.index, kind, scores)
                if kind == "ego":
                    assert scores["bias_eligible"] and scores["nearer_egocentric"] is True
                    ego_seen += 1
                else:
                    mirror_seen += 1
    assert ego_seen > 20 and mirror_seen > 20


def test_right_side_wrong_distance_is_a_placement_failure(generated):
    # walk from the ground truth away from the anchor's centre until the point leaves the region
    found = 0
    for inst in generated.instances(conditions=["c"], directions=["left", "right", "front"]):
        frame = inst.frames[0]
        truth = np.array(official_uv(np.asarray(inst.target), frame))
        centre = np.array(official_uv(np.asarray(case_of(generated, inst).anchor_centre), frame))
        away = (truth - centre) / max(1e-9, float(np.linalg.norm(truth - centre)))
        for k in np.arange(0.01, 0.2, 0.01):
            uv = np.clip(truth + k * away, 0, 1)
            scores = DiagnoseScorer().score(inst, answer(None, *uv), generated)
            if not scores["relation"]:
                if scores["step"] not in ("anchor", "viewpoint"):
                    assert scores["step"] == "placement"
                    assert not RelationScorer().score(inst, answer(None, *uv), generated)["success"]
                    found += 1
                break
    assert found > 10


def test_given_answers_cast_no_bias_vote(generated):
    for inst in generated.instances(conditions=["c"]):
        mirror = official_uv(mirrored_target(case_of(generated, inst)), inst.frames[0])
        scores = DiagnoseScorer().score(inst, answer(None, *mirror), generated)
        assert scores["bias_eligible"] is False and scores["nearer_egocentric"] is None
        assert scores["frame_shows"] == "observer view"


def test_unanswered_and_frameless_answers_are_not_diagnosed(generated):
    inst = generated.instances(conditions=["a"])[0]
    assert DiagnoseScorer().score(inst, unparseable("no json"), generated) == {"answered": False}
    assert DiagnoseScorer().score(inst, answer(999, 0.5, 0.5), generated) == {"answered": False}
    assert RelationScorer().score(inst, answer(None, 0.5, 0.5), generated) == {"answered": False}


def test_without_the_release_records_the_scorer_says_what_it_needs(generated):
    inst = generated.instances(conditions=["c"])[0]
    with pytest.raises(ValueError, match="placement records"):
        DiagnoseScorer().score(inst, answer(None, 0.5, 0.5), None)


def test_a_real_world_set_refuses_both_before_any_request(tmp_path):
    from pathlib import Path

    demo = load_realworld(Path(__file__).resolve().parents[2] / "examples" / "realworld_demo", cache_dir=tmp_path)
    with pytest.raises(ConfigError, match="diagnose, relation"):
        demo.check_scorers({"diagnose": DiagnoseScorer, "relation": RelationScorer})

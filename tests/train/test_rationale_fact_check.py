"""Every fact a rationale states is recomputed from the scene, independently, for every instance.

The recomputation here uses the camera's projection and the instance's records directly, not
:mod:`povagent.train.facts`: the frame named (it saw the anchor, the target projects inside it),
the side (the sentence's direction), the observer's facing (the observer-to-anchor heading in the
camera's axes), the anchor's pixel, and the answer (the ground truth's pixel; official L2 within
rounding, and 0 with exact answers).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from povagent.dataset.loader import load_dataset
from povagent.scoring.official import score_point
from povagent.train.examples import house_examples, make_strategy

SIDES = {"left": "LEFT", "right": "RIGHT", "front": "FRONT", "up": "ON TOP"}


def _facing(camera, observer_xz: np.ndarray, anchor_xz: np.ndarray) -> str:
    heading = np.array([anchor_xz[0] - observer_xz[0], 0.0, anchor_xz[1] - observer_xz[1]])
    right, _up, forward = camera.axes()  # rows: right, up, forward in world coordinates
    forward = np.array([forward[0], 0.0, forward[2]])  # the camera's heading on the floor (it looks down)
    forward /= np.linalg.norm(forward)
    across, ahead = float(heading @ right), float(heading @ forward)
    angle = math.degrees(math.atan2(across, ahead))
    if abs(angle) <= 45:
        return "away from the camera"
    if abs(angle) >= 135:
        return "towards the camera"
    return "towards the image's right" if angle > 0 else "towards the image's left"


@pytest.fixture(scope="module")
def examples(generated_release: Path) -> list:
    ds = load_dataset(generated_release)
    out = []
    for rationale in ("s-cot", "cot"):
        strategy = make_strategy(rationale)
        for house in ds.houses.values():
            for ex in house_examples(house, ds.instances(houses=[house.house_id]), rationale, strategy, seed=7):
                assert not isinstance(ex, tuple), ex
                out.append((rationale, ex, ds.instance(ex.id)))
    return out


def test_the_set_is_not_empty_and_has_every_condition(examples) -> None:
    assert {inst.condition.value for _, _, inst in examples} == {"a", "b", "c"}
    assert len(examples) > 100


def test_the_frame_named_saw_the_anchor_and_holds_the_target(examples) -> None:
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        answer = json.loads(ex.answer.splitlines()[-1])
        k = answer["selected_image"]
        stated = {int(m) for m in re.findall(r"Image (\d+)", ex.answer.split("Step 2")[0])}
        assert stated == {k}, ex.id
        frame = inst.frames[k]
        assert inst.anchor_object.objectId in frame.in_frame_hits
        proj = frame.camera.project(np.array([inst.target]))
        assert bool(proj.in_frame[0]), ex.id


def test_the_side_stated_is_the_sentences_direction(examples) -> None:
    for rationale, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        words = SIDES[inst.direction.value]
        if rationale == "s-cot":
            assert f"places the target {words} relative to" in ex.answer, ex.id
        others = [w for d, w in SIDES.items() if d != inst.direction.value and f"places the target {w} " in ex.answer]
        assert not others, ex.id


def test_the_facing_stated_is_the_observers_heading_seen_from_the_frame(examples) -> None:
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        k = json.loads(ex.answer.splitlines()[-1])["selected_image"]
        camera = inst.frames[k].camera
        obs = np.asarray(inst.observer_camera.position)[[0, 2]]
        anc = np.asarray(inst.anchor_object.position.as_tuple())[[0, 2]]
        expected = _facing(camera, obs, anc)
        step2 = ex.answer.split("Step 2")[1].split("Step 3")[0]
        assert expected in step2, (ex.id, expected, step2)


def test_the_anchor_pixel_stated_is_its_box_centre_projected(examples) -> None:
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        k = json.loads(ex.answer.splitlines()[-1])["selected_image"]
        box = inst.anchor_object.raw_metadata.axisAlignedBoundingBox
        pix = inst.frames[k].camera.project_pixels(np.array([[box.center.x, box.center.y, box.center.z]]))[0]
        step3 = ex.answer.split("Step 3")[1].split("Step 4")[0]
        x, y = (int(v) for v in re.search(r"\((-?\d+), (-?\d+)\)", step3).groups())
        assert (x, y) == (round(pix[0]), round(pix[1])), ex.id
        # every other view named: the frame saw the anchor, and the pixel is its centre there
        for j, ox, oy in re.findall(r"Image (\d+) near \((-?\d+), (-?\d+)\)", step3):
            other = inst.frames[int(j)]
            assert inst.anchor_object.objectId in other.in_frame_hits, ex.id
            opix = other.camera.project_pixels(np.array([[box.center.x, box.center.y, box.center.z]]))[0]
            assert (int(ox), int(oy)) == (round(opix[0]), round(opix[1])), ex.id


def test_the_answer_is_the_ground_truth_within_rounding_by_the_official_scorer(examples) -> None:
    for _, ex, inst in examples:
        answer = json.loads(ex.answer.splitlines()[-1])
        frame = inst.frames[answer.get("selected_image", 0)]
        score = score_point(inst, frame, float(answer["x"]), float(answer["y"]))
        w, h = frame.camera.width, frame.camera.height
        assert score.answered and score.l2 <= math.hypot(0.5 / w, 0.5 / h) + 1e-12, ex.id


def test_exact_answers_score_zero(generated_release: Path) -> None:
    ds = load_dataset(generated_release)
    house = next(iter(ds.houses.values()))
    strategy = make_strategy("none")
    n = 0
    for ex in house_examples(house, ds.instances(houses=[house.house_id]), "none", strategy, seed=0, exact=True):
        inst = ds.instance(ex.id)
        answer = json.loads(ex.answer)
        score = score_point(inst, inst.frames[answer.get("selected_image", 0)], answer["x"], answer["y"])
        assert score.l2 < 1e-12, ex.id
        n += 1
    assert n > 20


def test_the_wording_varies_with_the_seed_but_the_facts_do_not(generated_release: Path) -> None:
    ds = load_dataset(generated_release)
    house = next(iter(ds.houses.values()))
    insts = [i for i in ds.instances(houses=[house.house_id]) if i.condition.value == "a"]
    strategy = make_strategy("s-cot")
    a = [e.answer for e in house_examples(house, insts, "s-cot", strategy, seed=1)]
    b = [e.answer for e in house_examples(house, insts, "s-cot", strategy, seed=2)]
    assert a != b
    assert [x.splitlines()[-1] for x in a] == [x.splitlines()[-1] for x in b]
    assert a == [e.answer for e in house_examples(house, insts, "s-cot", strategy, seed=1)]

"""Every fact a rationale states is recomputed from the scene, independently, for every instance.

The recomputation here uses the camera's projection and the instance's records directly, not
:mod:`povagent.tasks.scene_facts`: the frame named (it saw the anchor, the target projects inside it),
the side (the sentence's direction), where the speaker stood (the observer camera on the floor,
in the frame camera's axes) and which way they faced (the observer-to-anchor heading in those
axes, in words and degrees), the anchor's pixel and box in the frame and in every other view
named, and the answer (the ground truth's pixel; official L2 within rounding, and 0 with exact
answers).
"""

from __future__ import annotations

import functools
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from povagent.dataset.loader import load_dataset
from povagent.scoring.normalized_l2 import score_point
from povagent.train.examples import house_examples, make_strategy

SIDES = {"left": "LEFT", "right": "RIGHT", "front": "FRONT", "up": "ON TOP"}


def _floor_axes(camera) -> tuple[np.ndarray, np.ndarray]:
    right, _up, forward = camera.axes()  # rows: right, up, forward in world coordinates
    forward = np.array([forward[0], 0.0, forward[2]])  # the camera's heading on the floor (it looks down)
    return right, forward / np.linalg.norm(forward)


def _heading_deg(camera, observer_xz: np.ndarray, anchor_xz: np.ndarray) -> float:
    heading = np.array([anchor_xz[0] - observer_xz[0], 0.0, anchor_xz[1] - observer_xz[1]])
    right, forward = _floor_axes(camera)
    return math.degrees(math.atan2(float(heading @ right), float(heading @ forward)))


def _facing(angle: float) -> str:
    if abs(angle) <= 45:
        return "away from the camera"
    if abs(angle) >= 135:
        return "towards the camera"
    return "towards the image's right" if angle > 0 else "towards the image's left"


def _sampled_box(camera, lo: np.ndarray, hi: np.ndarray, per_edge: int = 4000) -> tuple[float, float, float, float]:
    """The box's outline by brute force: points along its twelve edges (corners included), those
    more than 5 cm in front of the camera projected (the edges carry the outline's extremes)."""
    t = np.linspace(0.0, 1.0, per_edge)[:, None]
    points = []
    for axis in range(3):
        for a_high in (False, True):
            for b_high in (False, True):
                start = lo.copy()
                others = [a for a in range(3) if a != axis]
                start[others[0]] = hi[others[0]] if a_high else lo[others[0]]
                start[others[1]] = hi[others[1]] if b_high else lo[others[1]]
                end = start.copy()
                end[axis] = hi[axis]
                points.append(start + t * (end - start))
    pts = np.concatenate(points)
    pts = pts[camera.to_camera(pts)[:, 2] > 0.05]
    px = camera.project_pixels(pts)
    w, h = camera.width - 1, camera.height - 1
    return (min(max(px[:, 0].min(), 0), w), min(max(px[:, 1].min(), 0), h), min(max(px[:, 0].max(), 0), w), min(max(px[:, 1].max(), 0), h))


def _box_seen(camera, inst) -> tuple[float, float, float, float]:
    corners = np.asarray(inst.anchor_object.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float)
    return _sampled_box_once(camera, tuple(corners.min(axis=0)), tuple(corners.max(axis=0)))


@functools.cache
def _sampled_box_once(camera, lo: tuple[float, ...], hi: tuple[float, ...]) -> tuple[float, float, float, float]:
    """:func:`_sampled_box` once per camera and box: both rationales of an instance, and the
    instances of a house, name the same anchors in the same frames (about 500 boxes checked,
    35 distinct). A camera is a frozen dataclass: equal cameras are the same view."""
    return _sampled_box(camera, np.array(lo), np.array(hi))


SPAN = r", spanning x (\d+)-(\d+) and y (\d+)-(\d+)"


def _span_box(edges) -> list[int]:
    """``x0, x1, y0, y1`` as the text states them, as ``x0, y0, x1, y1``."""
    x0, x1, y0, y1 = (int(v) for v in edges)
    return [x0, y0, x1, y1]


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


def test_the_frame_named_has_the_anchors_centre_inside_it_when_any_frame_does(examples) -> None:
    named_off = 0
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        centre = np.array([inst.anchor_object.raw_metadata.axisAlignedBoundingBox.center.as_tuple()])
        usable = [
            f for f in inst.frames
            if inst.anchor_object.objectId in f.in_frame_hits and bool(f.camera.project(np.array([inst.target])).in_frame[0])
        ]
        k = json.loads(ex.answer.splitlines()[-1])["selected_image"]
        if any(bool(f.camera.project(centre).in_frame[0]) for f in usable):
            assert bool(inst.frames[k].camera.project(centre).in_frame[0]), ex.id
        else:
            named_off += 1
    assert named_off < len(examples) // 10


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
        angle = _heading_deg(camera, obs, anc)
        step2 = ex.answer.split("Step 2")[1].split("Step 3")[0]
        assert _facing(angle) in step2, (ex.id, angle, step2)
        turned = re.search(r"turned (?:(\d+)° to the (left|right) of|along) the camera's heading", step2)
        assert turned is not None, step2
        degrees = 0 if turned.group(1) is None else int(turned.group(1)) * (1 if turned.group(2) == "right" else -1)
        assert abs(degrees - angle) <= 0.5 or abs(abs(degrees) - 180) + abs(abs(angle) - 180) <= 0.5, (ex.id, angle, step2)


def test_where_the_speaker_stood_is_the_observer_camera_on_the_floor_seen_from_the_frame(examples) -> None:
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        k = json.loads(ex.answer.splitlines()[-1])["selected_image"]
        camera = inst.frames[k].camera
        right, forward = _floor_axes(camera)
        d = np.asarray(inst.observer_camera.position) - np.asarray(camera.position)
        d[1] = 0.0
        step2 = ex.answer.split("Step 2")[1].split("Step 3")[0]
        stood = re.search(r"stood (\d+\.\d\d) m to the (left|right) of the camera and (\d+\.\d\d) m (ahead of|behind) it", step2)
        assert stood is not None, step2
        across = float(stood.group(1)) * (1 if stood.group(2) == "right" else -1)
        ahead = float(stood.group(3)) * (1 if stood.group(4) == "ahead of" else -1)
        assert abs(across - float(d @ right)) <= 0.005 + 1e-9 and abs(ahead - float(d @ forward)) <= 0.005 + 1e-9, (ex.id, step2)


def test_the_anchor_pixel_and_box_stated_are_its_box_projected(examples) -> None:
    for _, ex, inst in examples:
        if inst.condition.value == "c":
            continue
        k = json.loads(ex.answer.splitlines()[-1])["selected_image"]
        box = inst.anchor_object.raw_metadata.axisAlignedBoundingBox
        centre = np.array([[box.center.x, box.center.y, box.center.z]])
        pix = inst.frames[k].camera.project_pixels(centre)[0]
        step3 = ex.answer.split("Step 3")[1].split("Step 4")[0]
        here, _, others = step3.partition("Image ")
        x, y = (int(v) for v in re.search(r"\((-?\d+), (-?\d+)\)", here).groups())
        assert (x, y) == (round(pix[0]), round(pix[1])), ex.id
        span = re.search(SPAN, here)
        assert span is not None, ex.id  # every teaching frame shows some of the anchor
        assert np.allclose(_span_box(span.groups()), _box_seen(inst.frames[k].camera, inst), atol=0.5 + 1e-6), (ex.id, here)
        # every other view named: the frame saw the anchor, the pixel is its centre there, the box its box
        views = re.findall(r"Image (\d+) near \((-?\d+), (-?\d+)\)(?:" + SPAN + ")?", "Image " + others if others else "")
        for j, ox, oy, *edges in views:
            other = inst.frames[int(j)]
            assert inst.anchor_object.objectId in other.in_frame_hits, ex.id
            opix = other.camera.project_pixels(centre)[0]
            assert (int(ox), int(oy)) == (round(opix[0]), round(opix[1])), ex.id
            assert all(edges), (ex.id, step3)  # the centre is in view, so some of the box is
            assert np.allclose(_span_box(edges), _box_seen(other.camera, inst), atol=0.5 + 1e-6), (ex.id, step3)


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


def test_the_example_in_docs_training_is_what_the_exporter_writes(generated_release: Path) -> None:
    docs = (Path(__file__).parents[2] / "docs" / "how-to" / "training.md").read_text()
    block = docs.split("An S-CoT rationale as exported", 1)[1].split("```text\n", 1)[1].split("\n  ```", 1)[0]
    shown = "\n".join(line.removeprefix("  ") for line in block.splitlines())
    ds = load_dataset(generated_release)
    inst = ds.instance("train_house_00001/pair_005/left/a")
    (ex,) = house_examples(ds.houses[inst.house_id], [inst], "s-cot", make_strategy("s-cot"), seed=0)
    assert not isinstance(ex, tuple)
    assert shown == ex.answer

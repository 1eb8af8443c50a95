"""The relation region: valid placements by the paper's rules, and their image in a frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.dataset.loader import load_dataset, placement_case
from povagent.geometry.camera import Camera
from povagent.geometry.counterfactual import mirrored_target
from povagent.geometry.ground_truth import AnchorBox, PlacementCase
from povagent.geometry.relation_region import MAX_GAP, NEAR_PLANE, SECTOR_HALF_ANGLE, region_in_frame, valid_placements
from povagent.scoring.diagnosis import BIAS_MARGIN, official_uv

BOX = AnchorBox(center_xz=(2.0, 0.0), half_xz=(0.5, 0.3), top=1.0)


def case(direction: str, anchor_type: str = "Sofa", surface: str = "on the floor", verdict: str = "appropriate") -> PlacementCase:
    # the observer at the origin faces +x: left is +z, right -z, front -x
    return PlacementCase(direction, BOX, anchor_type, (2.0, 0.5, 0.0), (2.0, 0.5, 0.0), (0.0, 1.5, 0.0), verdict, surface, (9.0, 9.0, 9.0))


def test_the_ground_truth_is_the_first_valid_placement():
    for direction in ("right", "left", "front", "up"):
        c = case(direction)
        assert valid_placements(c)[0] == pytest.approx(c.target())


def test_left_placements_stay_in_the_left_sector_beside_the_box_on_the_floor():
    points = valid_placements(case("left"))
    rel = points[:, [0, 2]] - np.array([2.0, 0.0])
    angles = np.degrees(np.arctan2(rel[:, 0], rel[:, 1]))  # angle from +z (the observer's left)
    assert np.all(points[:, 1] == pytest.approx(0.2))
    assert np.all(np.abs(angles) <= SECTOR_HALF_ANGLE + 1e-6)
    # the cube's centre stands clear of the box (the rule's 0.2 m is along the direction, so
    # on a diagonal the cube may touch a corner, as the official ground truth may)
    outside_box = (np.abs(rel[:, 0]) >= 0.5 + 0.1) | (np.abs(rel[:, 1]) >= 0.3 + 0.1)
    assert np.all(outside_box)
    assert np.max(np.linalg.norm(rel, axis=1)) <= math.hypot(0.5, 0.3) + 0.2 + MAX_GAP + 1e-9
    assert not np.any(rel[:, 1] < 0)  # nothing on the right side


def test_up_placements_cover_the_top_at_cube_height():
    points = valid_placements(case("up"))
    assert np.all(points[:, 1] == pytest.approx(1.2))
    assert points[:, 0].min() == pytest.approx(1.5) and points[:, 0].max() == pytest.approx(2.5)
    assert points[:, 2].min() == pytest.approx(-0.3) and points[:, 2].max() == pytest.approx(0.3)


def test_on_the_bed_placements_stay_on_its_top_on_their_side():
    points = valid_placements(case("right", anchor_type="Bed", surface="on the bed"))
    assert np.all(points[:, 1] == pytest.approx(1.2))
    assert np.all(points[:, 2] < 0)  # right is -z
    assert np.all(np.abs(points[:, 0] - 2.0) <= 0.5 + 1e-9) and np.all(np.abs(points[:, 2]) <= 0.3 + 1e-9)


def test_an_inappropriate_verdict_has_only_the_raw_placement():
    assert valid_placements(case("left", verdict="inappropriate")).tolist() == [[9.0, 9.0, 9.0]]


def test_a_frame_looking_away_has_an_empty_region():
    away = Camera.from_pose((0.0, 1.5, 0.0), yaw=270.0, horizon=0.0)  # looks along -x, the anchor behind it
    region = region_in_frame(valid_placements(case("left")), away)
    assert region.empty and not region.contains(256, 256) and region.margin(256, 256) is None


def test_the_region_is_the_side_of_the_anchor_in_the_observer_view():
    observer = Camera.from_pose((0.0, 1.5, 0.0), yaw=90.0, horizon=30.0)
    region = region_in_frame(valid_placements(case("left")), observer)
    truth = observer.project_pixels(np.array(case("left").target()))
    mirror = observer.project_pixels(mirrored_target(case("left")))
    assert region.contains(*truth) and not region.contains(*mirror)
    assert truth[0] < 256 < mirror[0]  # left of the image centre, the mirror to the right


@pytest.fixture(scope="module")
def generated(generated_release):
    return load_dataset(generated_release, check_images=False)


def test_the_region_contains_the_ground_truth_of_every_instance_in_every_frame_facing_it(generated):
    checked = 0
    for inst in generated.instances():
        placements = valid_placements(placement_case(generated.houses[inst.house_id].pairs[inst.pair_id], inst.direction))
        for frame in inst.frames:
            if frame.camera.project_point(inst.target)[2] <= NEAR_PLANE:
                continue  # behind the camera: the region leaves such samples out
            u, v = official_uv(np.asarray(inst.target), frame)
            assert region_in_frame(placements, frame.camera).contains(u * 512, v * 512), (inst.id, frame.index)
            checked += 1
    assert checked > 500


def test_the_region_excludes_the_mirrored_target_in_the_observer_view_when_they_are_apart(generated):
    apart = 0
    for inst in generated.instances(conditions=["c"], directions=["left", "right"]):
        c = placement_case(generated.houses[inst.house_id].pairs[inst.pair_id], inst.direction)
        frame = inst.frames[0]
        truth, mirror = official_uv(np.asarray(inst.target), frame), official_uv(mirrored_target(c), frame)
        if math.dist(truth, mirror) <= BIAS_MARGIN:
            continue
        apart += 1
        assert not region_in_frame(valid_placements(c), frame.camera).contains(mirror[0] * 512, mirror[1] * 512), inst.id
    assert apart >= 10

"""Counterfactual targets, hand-computed: the observer faces +x, the anchor's box is known.

Observer camera at (0, 1.5, 0), anchor at (2, 0.5, 0) with half sizes 0.5 (x) and 0.3 (z),
top 1.0: the official rule gives fwd = +x, right = up x fwd = (0, 0, -1), left = (0, 0, 1),
front = (-1, 0, 0). The viewing camera stands at (2, 1.5, -3) with yaw 0 (it looks along +z),
so its right axis is +x: the egocentric right is +x, left -x, front -z.
"""

from __future__ import annotations

import numpy as np
import pytest

from povagent.geometry.camera import Camera
from povagent.geometry.counterfactual import anchor_centre, egocentric_target, mirrored_target
from povagent.geometry.ground_truth import AnchorBox, PlacementCase

BOX = AnchorBox(center_xz=(2.0, 0.0), half_xz=(0.5, 0.3), top=1.0)
VIEW = Camera.from_pose((2.0, 1.5, -3.0), yaw=0.0, horizon=30.0)


def case(direction: str, anchor_type: str = "Sofa", surface: str = "on the floor", verdict: str = "appropriate") -> PlacementCase:
    return PlacementCase(direction, BOX, anchor_type, (2.0, 0.5, 0.0), (2.0, 0.5, 0.0), (0.0, 1.5, 0.0), verdict, surface, (9.0, 9.0, 9.0))


# (direction, ground truth, egocentric, mirrored) on the floor beside a sofa
FLOOR = [
    ("right", (2.0, 0.2, -0.5), (2.7, 0.2, 0.0), (2.0, 0.2, 0.5)),
    ("left", (2.0, 0.2, 0.5), (1.3, 0.2, 0.0), (2.0, 0.2, -0.5)),
    ("front", (1.3, 0.2, 0.0), (2.0, 0.2, -0.5), (1.3, 0.2, 0.0)),
    ("up", (2.0, 1.2, 0.0), (2.0, 1.2, 0.0), (2.0, 1.2, 0.0)),
]


@pytest.mark.parametrize(("direction", "truth", "ego", "mirror"), FLOOR)
def test_floor_targets_by_hand(direction, truth, ego, mirror):
    placed = case(direction)
    assert placed.target() == pytest.approx(truth)
    assert egocentric_target(placed, VIEW) == pytest.approx(ego)
    assert mirrored_target(placed) == pytest.approx(mirror)


# a bed with the target on the bed: left/right sit 0.2 m from the centre, on the top
@pytest.mark.parametrize(("direction", "truth", "ego", "mirror"), [
    ("right", (2.0, 1.2, -0.2), (2.2, 1.2, 0.0), (2.0, 1.2, 0.2)),
    ("left", (2.0, 1.2, 0.2), (1.8, 1.2, 0.0), (2.0, 1.2, -0.2)),
])  # fmt: skip
def test_on_the_anchor_targets_by_hand(direction, truth, ego, mirror):
    placed = case(direction, anchor_type="Bed", surface="on the bed")
    assert placed.target() == pytest.approx(truth)
    assert egocentric_target(placed, VIEW) == pytest.approx(ego)
    assert mirrored_target(placed) == pytest.approx(mirror)


def test_egocentric_front_on_another_surface_uses_the_anchor_top():
    # "on the shelf": the release has no shelf box, so the anchor's top stands in (y = 1.2)
    assert egocentric_target(case("front", surface="on the shelf"), VIEW) == pytest.approx((2.0, 1.2, -0.5))


@pytest.mark.parametrize("direction", ["right", "left", "front", "up"])
def test_a_camera_facing_the_observers_way_gives_the_ground_truth(direction):
    along = Camera.from_pose((-1.0, 1.5, 0.0), yaw=90.0, horizon=0.0)  # looks along +x, like the observer
    c = case(direction)
    assert egocentric_target(c, along) == pytest.approx(c.target())


def test_the_cameras_tilt_does_not_change_the_egocentric_target():
    level = Camera.from_pose(VIEW.position, yaw=0.0, horizon=0.0)
    assert egocentric_target(case("right"), level) == pytest.approx(egocentric_target(case("right"), VIEW))


def test_a_camera_facing_the_other_way_swaps_left_and_right():
    against = Camera.from_pose((5.0, 1.5, 0.0), yaw=270.0, horizon=0.0)  # looks along -x
    assert egocentric_target(case("right"), against) == pytest.approx(case("left").target())
    assert egocentric_target(case("front"), against) == pytest.approx((2.7, 0.2, 0.0))  # the side facing it


@pytest.mark.parametrize("direction", ["right", "left", "front", "up"])
def test_without_an_appropriate_verdict_every_reading_keeps_the_raw_placement(direction):
    c = case(direction, verdict="inappropriate")
    assert egocentric_target(c, VIEW) == pytest.approx((9.0, 9.0, 9.0))
    assert mirrored_target(c) == pytest.approx((9.0, 9.0, 9.0))


def test_the_anchor_centre_is_the_box_centre():
    c = PlacementCase("right", BOX, "Sofa", (2.0, 0.0, 0.0), (2.0, 0.5, 0.1), (0.0, 1.5, 0.0), "appropriate", "on the floor", (0, 0, 0))
    assert anchor_centre(c) == pytest.approx((2.0, 0.5, 0.1))


def test_counterfactuals_are_projected_with_the_official_rules():
    from povagent.dataset.instances import Frame
    from povagent.scoring.diagnosis import official_uv

    frame = Frame(0, "f.png", __import__("pathlib").Path("f.png"), VIEW)
    behind = np.array([2.0, 1.0, -5.0])  # behind the camera at z = -3 looking +z
    assert official_uv(behind, frame) == (0.5, 0.5)
    far_right = np.array([40.0, 1.5, 0.0])  # in front, far outside the frame's right edge
    u, v = official_uv(far_right, frame)
    assert u == 1.0 and 0.0 < v < 1.0

"""Scene facts by hand: which way an observer faces seen from a camera, image directions, the teaching frame."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import AxisAlignedBoundingBox, Condition, Direction, RawMetadata, SceneObject, Vec3
from povagent.geometry.camera import Camera
from povagent.tasks.scene_facts import facing_angle, facing_words, gt_pixel, image_direction, teaching_frame

# an observer at the origin facing +x (the anchor 2 m along +x)
OBSERVER = np.array([0.0, 0.0])
ANCHOR = np.array([2.0, 0.0])


@pytest.mark.parametrize(
    ("yaw", "facing"),
    [
        (90.0, "away from the camera"),  # the camera looks along +x too
        (-90.0, "towards the camera"),  # the camera looks along -x
        (0.0, "towards the image's right"),  # the camera looks along +z; its right is +x
        (180.0, "towards the image's left"),  # the camera looks along -z; its right is -x
        (60.0, "away from the camera"),  # 30 degrees off: still away
        (30.0, "towards the image's right"),  # 60 degrees off: sideways
    ],
)
def test_facing_is_the_observers_heading_in_the_cameras_frame(yaw: float, facing: str) -> None:
    camera = Camera.from_pose((5.0, 0.9, 5.0), yaw, 30.0)
    assert facing_words(facing_angle(camera, OBSERVER, ANCHOR)) == facing


@pytest.mark.parametrize(
    ("du", "dv", "words"),
    [(1, 0, "right"), (-1, 0, "left"), (0, -1, "top"), (0, 1, "bottom"), (1, -1, "upper right"), (-1, 1, "lower left")],
)
def test_image_directions_read_v_downwards(du: float, dv: float, words: str) -> None:
    assert image_direction(du, dv) == words


def test_a_point_behind_or_outside_the_camera_has_no_pixel() -> None:
    camera = Camera.from_pose((0.0, 1.0, 0.0), 0.0, 0.0)  # looking along +z, level
    assert gt_pixel(camera, (0.0, 1.0, 2.0)) == pytest.approx((256.0, 256.0))
    assert gt_pixel(camera, (0.0, 1.0, -2.0)) is None
    assert gt_pixel(camera, (50.0, 1.0, 2.0)) is None


def _box_object(object_type: str, centre, size) -> SceneObject:
    (cx, cy, cz), (hx, hy, hz) = centre, (s / 2 for s in size)
    corners = [[cx + sx * hx, cy + sy * hy, cz + sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    box = AxisAlignedBoundingBox(center=Vec3(x=cx, y=cy, z=cz), size=Vec3(x=size[0], y=size[1], z=size[2]), cornerPoints=corners)
    return SceneObject(
        objectId=f"{object_type}|1", position=Vec3(x=cx, y=cy, z=cz), raw_metadata=RawMetadata(objectType=object_type, axisAlignedBoundingBox=box)
    )


def test_the_teaching_frame_has_the_anchors_centre_in_view_before_it_has_the_furniture(tmp_path) -> None:
    # a 4 m sofa along x, centred at z = 4; the target just left of its right end
    anchor = _box_object("Sofa", (0.0, 0.4, 4.0), (4.0, 0.8, 1.0))
    furniture = _box_object("Television", (3.0, 0.5, 1.0), (1.0, 1.0, 0.3))
    target = (1.8, 0.2, 3.2)
    aside = Camera.from_pose((2.0, 0.9, 0.5), 20.0, 30.0)  # sees the sofa's end and the target, not its centre
    ahead = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 30.0)  # sees the sofa's centre and the target
    assert gt_pixel(aside, target) and gt_pixel(ahead, target) and gt_pixel(ahead, (0.0, 0.4, 4.0))
    assert gt_pixel(aside, (0.0, 0.4, 4.0)) is None
    frames = (
        Frame(0, "exploration_images/frame_000.png", tmp_path / "0.png", aside, frozenset({anchor.objectId, furniture.objectId})),
        Frame(1, "exploration_images/frame_001.png", tmp_path / "1.png", ahead, frozenset({anchor.objectId})),
    )
    instance = Instance("h", "p", Direction.LEFT, Condition.INFERRED, "s", frames, target, furniture, anchor, Camera.from_pose((2.5, 1.55, 1.5), 0.0, 20.0))
    assert teaching_frame(instance).index == 1
    # without a frame showing the anchor's centre, the one with the furniture teaches
    assert teaching_frame(replace(instance, frames=(frames[0], replace(frames[1], in_frame_hits=frozenset())))).index == 0

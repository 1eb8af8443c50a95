"""Scene facts by hand: which way an observer faces seen from a camera, and image directions."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.geometry.camera import Camera
from povagent.train.facts import facing_relative_to, gt_pixel, image_direction

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
    assert facing_relative_to(camera, OBSERVER, ANCHOR) == facing


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

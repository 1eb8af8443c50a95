"""The 2D box around a 3D box: its projected corners, or, when part of the box is behind the
camera, the part in front of the near plane, exactly.

The reference here is brute force: thousands of points along each of the box's twelve edges
(the outline's extremes lie on edges), those deeper than the near plane projected and boxed.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from povagent.geometry.box_outline import NEAR_PLANE, outline
from povagent.geometry.camera import Camera
from povagent.geometry.triangulation import optical_depth

# an exploration-style camera: 0.9 m high, 30 degrees down, looking along +z
CAMERA = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 30.0)


def sampled_outline(camera: Camera, lo, hi, per_edge: int = 20000):
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    t = np.linspace(0.0, 1.0, per_edge)[:, None]
    points = []
    for axis in range(3):
        for fixed in itertools.product((0, 1), repeat=2):
            start, end = lo.copy(), lo.copy()
            others = [a for a in range(3) if a != axis]
            for a, high in zip(others, fixed):
                start[a] = end[a] = hi[a] if high else lo[a]
            end[axis] = hi[axis]
            points.append(start + t * (end - start))
    pts = np.concatenate(points)
    pts = pts[optical_depth(camera, pts) > NEAR_PLANE]
    px = camera.project_pixels(pts)
    w, h = camera.width - 1.0, camera.height - 1.0
    return (np.clip(px[:, 0].min(), 0, w), np.clip(px[:, 1].min(), 0, h), np.clip(px[:, 0].max(), 0, w), np.clip(px[:, 1].max(), 0, h))


def test_a_box_wholly_in_front_is_outlined_by_its_projected_corners() -> None:
    lo, hi = np.array([-0.4, 0.0, 2.0]), np.array([0.3, 0.8, 2.6])
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    px = CAMERA.project_pixels(corners)
    expected = (px[:, 0].min(), px[:, 1].min(), px[:, 0].max(), px[:, 1].max())
    assert outline(CAMERA, lo, hi) == pytest.approx(expected)


@pytest.mark.parametrize(
    ("lo", "hi"),
    [
        ((0.3, 0.0, -1.0), (1.0, 0.9, 2.0)),  # a low counter running past the camera's right
        ((0.2, 0.0, -1.0), (1.2, 0.95, 1.5)),  # one reaching above the camera: its top edge leaves the image
        ((-1.47, 0.0, -0.91), (0.04, 0.6, 0.26)),  # a bed beside it on the left, mostly behind
        ((-0.09, 0.0, -0.94), (0.14, 1.41, 1.37)),  # a tall narrow box the camera stands inside
    ],
)
def test_a_box_partly_behind_is_outlined_by_its_part_in_front(lo, hi) -> None:
    assert np.any(optical_depth(CAMERA, np.array([lo, hi])) <= NEAR_PLANE)  # the case is what it says
    got = outline(CAMERA, lo, hi)
    assert got is not None
    assert got == pytest.approx(sampled_outline(CAMERA, lo, hi), abs=0.5)


def test_a_box_wholly_behind_has_no_outline() -> None:
    assert outline(CAMERA, (-1.0, 0.0, -3.0), (1.0, 1.0, -1.0)) is None

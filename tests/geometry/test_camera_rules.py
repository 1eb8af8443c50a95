"""The AI2-THOR camera rules as POVBENCH.md states them, one per test.

Facts ("Camera"): yaw y and horizon h in degrees, positive horizon looks down; right =
(cos y, 0, -sin y), forward = (sin y cos h, -sin h, cos y cos h), up = (sin y sin h, cos h,
cos y sin h); with d = point - cam_pos, (xc, yc, zc) = (d.right, d.up, d.forward),
f = (W/2) / tan(fov/2), u = f xc/zc + W/2, v = H/2 - f yc/zc, normalized u/W, v/H; a point with
zc <= 1e-6 is behind the camera.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.geometry.camera import BEHIND_EPSILON, Camera

YAW, HORIZON = 30.0, 20.0


def axes_from_the_sheet(yaw, horizon):
    y, h = math.radians(yaw), math.radians(horizon)
    right = (math.cos(y), 0.0, -math.sin(y))
    forward = (math.sin(y) * math.cos(h), -math.sin(h), math.cos(y) * math.cos(h))
    up = (math.sin(y) * math.sin(h), math.cos(h), math.cos(y) * math.sin(h))
    return np.array([right, up, forward])


def test_camera_axes_are_the_sheets_right_up_forward():
    cam = Camera.from_pose((1.0, 1.5, -2.0), YAW, HORIZON)
    assert np.allclose(cam.axes(), axes_from_the_sheet(YAW, HORIZON), atol=1e-12)


@pytest.mark.parametrize("point", [(2.0, 0.3, 1.0), (-1.0, 2.5, 4.0), (0.2, -1.0, 0.5)])
def test_a_point_projects_as_the_sheet_says(point):
    pos = np.array([0.5, 1.5, -1.0])
    cam = Camera.from_pose(pos, YAW, HORIZON, fov=100.0)
    xc, yc, zc = axes_from_the_sheet(YAW, HORIZON) @ (np.array(point) - pos)
    f = 256.0 / math.tan(math.radians(50.0))
    u, v, depth = cam.project_point(point)
    assert depth == pytest.approx(zc, abs=1e-12)
    assert (u, v) == pytest.approx(((f * xc / zc + 256.0) / 512.0, (256.0 - f * yc / zc) / 512.0), abs=1e-12)
    p = cam.project(np.array([point]))
    assert p.normalized[0] == pytest.approx([u, v], abs=1e-12)
    assert cam.project_pixels(np.array([point]))[0] == pytest.approx([u * 512, v * 512], abs=1e-9)


def test_positive_horizon_looks_down():
    cam = Camera.from_pose((0.0, 1.5, 0.0), 0.0, 30.0)
    # a point straight ahead at eye height is above the image centre when looking down
    u, v, _ = cam.project_point((0.0, 1.5, 3.0))
    assert u == pytest.approx(0.5) and v < 0.5


def test_in_frame_needs_u_and_v_inside_and_the_point_in_front():
    cam = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0, fov=90.0)
    # x/z = +-1.2 -> u = 1.1 or -0.1; y/z likewise for v: each just outside one edge
    p = cam.project(np.array([[0.0, 0.0, 2.0], [0.0, 1.2, 1.0], [0.0, -1.2, 1.0], [1.2, 0.0, 1.0], [-1.2, 0.0, 1.0], [0.0, 0.0, -2.0]]))
    assert p.in_frame.tolist() == [True, False, False, False, False, False]
    assert p.in_front.tolist() == [True, True, True, True, True, False]


def test_the_frame_edges_are_in_frame():
    cam = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0, fov=90.0)
    e = 256.0 / cam.focal_px
    p = cam.project(np.array([[-e, e, 1.0], [e, -e, 1.0]]))
    assert p.normalized.tolist() == [[0.0, 0.0], [1.0, 1.0]]
    assert p.in_frame.tolist() == [True, True]


def test_a_camera_is_a_value_that_cannot_be_moved():
    import dataclasses

    cam = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cam.yaw = 90.0  # type: ignore[misc]
    projection = cam.project(np.array([[0.0, 0.0, 1.0]]))
    with pytest.raises(dataclasses.FrozenInstanceError):
        projection.depth = np.zeros(1)  # type: ignore[misc]


def test_the_behind_threshold_is_1e_6_inclusive():
    assert BEHIND_EPSILON == 1e-6
    cam = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0)
    assert math.isnan(cam.project_point((0.0, 0.0, 1e-6))[0])
    assert not math.isnan(cam.project_point((0.0, 0.0, 2e-6))[0])
    p = cam.project(np.array([[0.0, 0.0, 1e-6], [0.0, 0.0, 2e-6]]))
    assert p.in_front.tolist() == [False, True]
    assert np.isnan(p.normalized[0]).all()


def test_focal_length_comes_from_the_width_on_a_non_square_frame():
    cam = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0, fov=90.0, width=640, height=480)
    # f = 320: x/z = 1 lands on the right edge, y/z = 0.5 lands at v = (240 - 160)/480
    u, v, _ = cam.project_point((1.0, 0.5, 1.0))
    assert (u, v) == pytest.approx((1.0, 80.0 / 480.0), abs=1e-12)


def test_a_camera_defaults_to_the_benchmark_frame_and_fov():
    cam = Camera((0.0, 0.0, 0.0), 0.0, 0.0)
    assert (cam.fov, cam.width, cam.height) == (100.0, 512, 512)
    posed = Camera.from_pose([0, 0, 0], 0, 0)
    assert (posed.fov, posed.width, posed.height) == (100.0, 512, 512)


def test_the_solver_reads_the_pinhole_as_values_with_the_principal_point_at_the_centre():
    # ViewCamera's contract: (fx, fy, cx, cy) on the optical axes (right, down, forward) give
    # project_pixels' pixel; square pixels (f from the width), the content is the whole image
    cam = Camera.from_pose((0.5, 1.5, -1.0), YAW, HORIZON, fov=90.0, width=640, height=480)
    assert cam.intrinsics == pytest.approx((320.0, 320.0, 320.0, 240.0), abs=1e-9)
    assert cam.content_box == (0.0, 0.0, 640.0, 480.0)
    fx, fy, cx, cy = cam.intrinsics
    point = np.array([1.0, 0.8, 2.0])
    x, y, z = cam.optical_axes() @ (point - np.asarray(cam.position))
    assert (fx * x / z + cx, fy * y / z + cy) == pytest.approx(tuple(cam.project_pixels(point)), abs=1e-9)

"""The AI2-THOR camera: projection, back-projection, conventions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from povagent.geometry.camera import Camera

yaws = st.floats(-360, 360, allow_nan=False)
horizons = st.floats(-60, 60, allow_nan=False)
fovs = st.floats(30, 120, allow_nan=False)
coords = st.floats(-10, 10, allow_nan=False)


def test_point_straight_ahead_projects_to_the_centre_for_yaw_zero():
    cam = Camera.from_pose([0, 1.5, 0], yaw=0, horizon=0, fov=90)
    assert np.allclose(cam.project(np.array([0, 1.5, 4.0])).normalized, [0.5, 0.5])


def test_positive_x_is_right_and_lower_y_is_down_at_yaw_zero():
    # fov 90 -> f = W/2: a point 1 m right and 1 m below at 2 m depth lands at (0.75, 0.75)
    cam = Camera.from_pose([0, 1.5, 0], yaw=0, horizon=0, fov=90)
    assert np.allclose(cam.project(np.array([1.0, 0.5, 2.0])).normalized, [0.75, 0.75])


def test_yaw_ninety_looks_along_positive_x():
    cam = Camera.from_pose([0, 1.0, 0], yaw=90, horizon=0, fov=90)
    assert np.allclose(cam.project(np.array([3.0, 1.0, 0.0])).normalized, [0.5, 0.5])
    # right of a camera looking along +x is -z in Unity's left-handed frame
    assert cam.project(np.array([3.0, 1.0, -1.0])).normalized[0] > 0.5


def test_positive_horizon_looks_down():
    cam = Camera.from_pose([0, 1.0, 0], yaw=0, horizon=30, fov=90)
    ahead_and_down = np.array([0.0, 1.0 - math.tan(math.radians(30)) * 2.0, 2.0])
    assert np.allclose(cam.project(ahead_and_down).normalized, [0.5, 0.5])


def test_point_behind_the_camera_is_flagged_not_projected():
    cam = Camera.from_pose([0, 1.0, 0], yaw=0, horizon=0)
    p = cam.project(np.array([0.0, 1.0, -2.0]))
    assert not p.in_front and not p.in_frame
    assert np.isnan(p.normalized).all()


def test_projection_is_vectorized_over_many_points():
    cam = Camera.from_pose([0, 1.0, 0], yaw=0, horizon=0, fov=90)
    pts = np.array([[0, 1, 2], [1, 1, 2], [0, 1, -2]], dtype=float)
    p = cam.project(pts)
    assert p.normalized.shape == (3, 2)
    assert p.in_front.tolist() == [True, True, False]


@settings(max_examples=200, deadline=None)
@given(yaws, horizons, fovs, st.floats(0, 511), st.floats(0, 511), st.floats(0.2, 20))
def test_pixel_back_projected_at_a_depth_projects_back_to_the_same_pixel(yaw, horizon, fov, u, v, depth):
    cam = Camera.from_pose([1.0, 0.9, -2.0], yaw, horizon, fov)
    world = cam.point_at_depth(np.array([u, v]), depth)
    assert np.allclose(cam.project_pixels(world), [u, v], atol=1e-6)


@settings(max_examples=200, deadline=None)
@given(yaws, horizons, fovs, st.floats(0.1, 30))
def test_a_point_on_the_optical_axis_projects_to_the_image_centre(yaw, horizon, fov, distance):
    cam = Camera.from_pose([0.5, 1.2, 0.5], yaw, horizon, fov)
    forward = cam.axes()[2]
    p = cam.project(np.asarray(cam.position) + distance * forward)
    assert np.allclose(p.normalized, [0.5, 0.5], atol=1e-9)
    assert p.in_frame


@settings(max_examples=200, deadline=None)
@given(yaws, st.floats(5, 60), st.floats(0, 511), st.floats(300, 511))
def test_floor_point_of_a_pixel_lies_on_the_floor_and_projects_back(yaw, horizon, u, v):
    # a downward-looking camera: lower half pixels hit the floor in front of it
    cam = Camera.from_pose([0.0, 0.9, 0.0], yaw, horizon, 100)
    p = cam.point_on_plane(np.array([u, v]), 0.0)
    assert abs(p[1]) < 1e-9
    assert np.allclose(cam.project_pixels(p), [u, v], atol=1e-6)


def test_ray_through_the_centre_is_the_forward_axis():
    cam = Camera.from_pose([0, 1, 0], yaw=37, horizon=12)
    assert np.allclose(cam.ray(np.array([256.0, 256.0])), cam.axes()[2])


def test_a_pixel_past_float_range_has_a_nan_ray_without_a_warning():
    """A model may answer a number past float range (inf): that pixel has no ray, the others
    keep theirs, and numpy is not asked to compute inf * 0 (which warned on every call)."""
    import warnings

    cam = Camera.from_pose([0, 1, 0], yaw=37, horizon=12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rays = cam.ray(np.array([[np.inf, 10.0], [256.0, 256.0], [np.nan, 0.0]]))
    assert np.isnan(rays[0]).all() and np.isnan(rays[2]).all()
    assert np.allclose(rays[1], cam.axes()[2])


def test_axes_are_orthonormal():
    cam = Camera.from_pose([0, 1, 0], yaw=123, horizon=-17)
    r = cam.axes()
    assert np.allclose(r @ r.T, np.eye(3))


@settings(max_examples=300, deadline=None)
@given(yaws, horizons, fovs, coords, coords, coords)
def test_single_point_projection_agrees_with_the_vectorized_one(yaw, horizon, fov, x, y, z):
    cam = Camera.from_pose([0.3, 1.1, -0.7], yaw, horizon, fov, 512, 384)
    u, v, depth = cam.project_point((x, y, z))
    p = cam.project(np.array([x, y, z]))
    assert depth == pytest.approx(float(p.depth), abs=1e-9)
    if p.in_front:
        # agreement to rounding: near the camera plane u, v grow large, and so does their last bit
        assert (u, v) == (
            pytest.approx(float(p.normalized[0]), rel=1e-12, abs=1e-9),
            pytest.approx(float(p.normalized[1]), rel=1e-12, abs=1e-9),
        )
    else:
        assert math.isnan(u) and math.isnan(v)


def test_floor_offsets_are_metres_to_the_cameras_right_and_along_its_heading():
    # yaw 90 looks along +x, so its right is -z; the horizon's tilt does not turn the heading
    cam = Camera.from_pose([1.0, 0.9, 2.0], yaw=90, horizon=30)
    assert cam.floor_offset((4.0, 0.0, 2.0)) == pytest.approx((0.0, 3.0))
    assert cam.floor_offset((1.0, 5.0, 0.5)) == pytest.approx((1.5, 0.0))  # height is ignored
    assert cam.floor_offset((0.0, 0.0, 3.0)) == pytest.approx((-1.0, -1.0))  # behind, to the left


@settings(max_examples=50, deadline=None)
@given(yaws, horizons, coords, coords)
def test_a_floor_offset_leads_back_to_its_point_on_the_floor(yaw, horizon, x, z):
    cam = Camera.from_pose([0.3, 0.9, -1.2], yaw=yaw, horizon=horizon)
    right, ahead = cam.floor_offset((x, 1.7, z))
    assert np.allclose(cam.floor_point(right, ahead), [x, 0.0, z], atol=1e-9)
    # the offset's axes are the camera's right and its forward laid flat
    r, _, f = cam.axes()
    flat = np.array([f[0], 0.0, f[2]]) / math.hypot(f[0], f[2])
    d = np.array([x - 0.3, 0.0, z + 1.2])
    assert (right, ahead) == pytest.approx((float(d @ r), float(d @ flat)), abs=1e-9)

"""Rigid transforms, quaternions, interpolation and the REP 103/105 frame conventions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.geometry.goals import PoseConvention
from povagent.ros.transforms import (
    RigidTransform,
    TransformProblem,
    interpolate,
    pose_convention,
    quaternion_from_rotation,
    rotation_angle,
    rotation_from_quaternion,
)


def yaw(deg: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(math.radians(deg) / 2), math.cos(math.radians(deg) / 2))


def test_a_quaternion_and_its_rotation_convert_both_ways():
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q = q if q[3] >= 0 else -q
        assert np.allclose(quaternion_from_rotation(rotation_from_quaternion(q)), q, atol=1e-12)


def test_a_yaw_of_90_degrees_turns_x_to_y():
    assert np.allclose(rotation_from_quaternion(yaw(90)) @ [1, 0, 0], [0, 1, 0], atol=1e-12)


def test_interpolation_is_linear_in_translation_and_spherical_in_rotation():
    a = RigidTransform((0.0, 0.0, 0.0), yaw(0))
    b = RigidTransform((2.0, 4.0, 0.0), yaw(90))
    mid = interpolate(a, b, 0.25)
    assert mid.translation == pytest.approx((0.5, 1.0, 0.0))
    assert rotation_angle(np.eye(3), rotation_from_quaternion(mid.rotation)) == pytest.approx(22.5)


def test_interpolation_takes_the_shorter_way_round():
    # 170 and -170 degrees are 20 degrees apart, not 340
    mid = interpolate(RigidTransform((0, 0, 0), yaw(170)), RigidTransform((0, 0, 0), yaw(-170)), 0.5)
    assert rotation_angle(rotation_from_quaternion(yaw(180)), rotation_from_quaternion(mid.rotation)) == pytest.approx(0.0, abs=1e-9)


def test_a_transform_with_nan_is_refused_naming_what():
    with pytest.raises(TransformProblem, match="odom: the translation holds NaN"):
        RigidTransform.checked((float("nan"), 0, 0), (0, 0, 0, 1), "odom")
    with pytest.raises(TransformProblem, match="rotation holds NaN"):
        RigidTransform.checked((0, 0, 0), (0, 0, float("nan"), 1))


def test_a_quaternion_far_from_unit_is_refused_and_a_near_one_normalized():
    with pytest.raises(TransformProblem, match="norm"):
        RigidTransform.checked((0, 0, 0), (0, 0, 0, 0))
    t = RigidTransform.checked((0, 0, 0), (0, 0, 0, 1.0005))
    assert t.rotation == (0.0, 0.0, 0.0, 1.0)


def test_a_matrix_round_trips_through_a_transform():
    m = np.eye(4)
    m[:3, :3] = rotation_from_quaternion(yaw(33))
    m[:3, 3] = (1, 2, 3)
    assert np.allclose(RigidTransform.from_matrix(m).matrix(), m, atol=1e-12)


@pytest.mark.parametrize(("frame", "convention"), [
    ("camera_color_optical_frame", PoseConvention.OPENCV),
    ("head_camera_optical", PoseConvention.OPENCV),
    ("camera_link", PoseConvention.ROS),
    ("base_link", PoseConvention.ROS),
])
def test_an_images_frame_name_says_its_axis_convention(frame, convention):
    assert pose_convention(frame) == convention

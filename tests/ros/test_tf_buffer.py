"""The transform tree: chains, interpolation at an image's stamp, the tolerance, odometry."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from povagent.ros.tf_buffer import PoseUnavailable, TransformBuffer
from povagent.ros.transforms import RigidTransform, rotation_angle

S = 1_000_000_000  # one second in ns


def yawed(x: float, y: float, deg: float, z: float = 0.0) -> RigidTransform:
    h = math.radians(deg) / 2
    return RigidTransform((x, y, z), (0.0, 0.0, math.sin(h), math.cos(h)))


MOUNT = RigidTransform((0.1, 0.0, 0.9), (-0.5, 0.5, -0.5, 0.5))  # base_link -> optical: z forward, x right, y down


@pytest.fixture
def buffer() -> TransformBuffer:
    b = TransformBuffer(tolerance_s=0.2)
    b.add("base_link", "camera_optical_frame", 0, MOUNT, static=True)
    b.add("map", "odom", 0, yawed(1.0, 0.0, 0.0), static=True)
    b.add("odom", "base_link", 10 * S, yawed(0.0, 0.0, 0.0))
    b.add("odom", "base_link", 10 * S + 4 * S // 10, yawed(2.0, 0.0, 90.0))
    return b


def test_a_chain_composes_parent_to_child_poses(buffer):
    pose = buffer.lookup("map", "camera_optical_frame", 10 * S)
    assert np.allclose(pose, yawed(1.0, 0, 0).matrix() @ yawed(0, 0, 0).matrix() @ MOUNT.matrix())
    assert np.allclose(pose[:3, 2], [1, 0, 0], atol=1e-12)  # the optical z axis looks along the base's x


def test_a_stamp_between_two_samples_is_interpolated(buffer):
    pose = buffer.lookup("map", "base_link", 10 * S + S // 10)  # a quarter of the way
    assert np.allclose(pose[:3, 3], [1.5, 0.0, 0.0])
    assert rotation_angle(np.eye(3), pose[:3, :3]) == pytest.approx(22.5)


def test_a_stamp_within_tolerance_of_the_last_sample_takes_it(buffer):
    assert np.allclose(buffer.lookup("odom", "base_link", 10 * S + 5 * S // 10), yawed(2.0, 0.0, 90.0).matrix())


def test_a_stamp_beyond_the_tolerance_is_refused_not_extrapolated(buffer):
    with pytest.raises(PoseUnavailable, match=r"0\.300 s from the image's stamp \(tolerance 0\.2 s\)"):
        buffer.lookup("map", "camera_optical_frame", 10 * S + 7 * S // 10)


def test_a_gap_wider_than_twice_the_tolerance_refuses_stamps_in_its_middle():
    b = TransformBuffer(tolerance_s=0.2)
    b.add("map", "base_link", 0, yawed(0, 0, 0))
    b.add("map", "base_link", 2 * S, yawed(2, 0, 0))
    with pytest.raises(PoseUnavailable):
        b.lookup("map", "base_link", S)


def test_frames_that_no_chain_joins_are_refused_naming_them(buffer):
    with pytest.raises(PoseUnavailable, match="no transform chain joins 'map' and 'camera2'"):
        buffer.lookup("map", "camera2", 10 * S)


def test_the_inverse_direction_is_the_inverse_transform(buffer):
    forward = buffer.lookup("map", "camera_optical_frame", 10 * S)
    assert np.allclose(buffer.lookup("camera_optical_frame", "map", 10 * S) @ forward, np.eye(4))


def test_a_leading_slash_names_the_same_frame(buffer):
    assert np.allclose(buffer.lookup("/map", "/base_link", 10 * S), buffer.lookup("map", "base_link", 10 * S))


def test_odometry_is_the_edge_from_its_frame_to_its_child():
    b = TransformBuffer()
    pose = SimpleNamespace(position=SimpleNamespace(x=1.0, y=2.0, z=0.0), orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0))
    msg = SimpleNamespace(header=SimpleNamespace(frame_id="odom", stamp=SimpleNamespace(sec=5, nanosec=0)), child_frame_id="base_link",
                          pose=SimpleNamespace(pose=pose))
    b.add_odometry(msg)
    assert np.allclose(b.lookup("odom", "base_link", 5 * S)[:3, 3], [1, 2, 0])


def test_samples_older_than_the_cache_span_are_forgotten():
    b = TransformBuffer(tolerance_s=0.2, cache_s=5.0)
    for t in range(20):
        b.add("map", "base_link", t * S, yawed(t, 0, 0))
    with pytest.raises(PoseUnavailable):
        b.lookup("map", "base_link", 2 * S)
    assert np.allclose(b.lookup("map", "base_link", 19 * S)[:3, 3], [19, 0, 0])


def test_a_flood_of_samples_keeps_only_the_newest_per_edge():
    from povagent.ros.tf_buffer import MAX_SAMPLES_PER_EDGE

    b = TransformBuffer(tolerance_s=0.0, cache_s=1e6)
    for t in range(MAX_SAMPLES_PER_EDGE + 5):
        b.add("map", "base_link", t, yawed(t, 0, 0))
    with pytest.raises(PoseUnavailable):
        b.lookup("map", "base_link", 0)
    assert np.allclose(b.lookup("map", "base_link", MAX_SAMPLES_PER_EDGE + 4)[:3, 3], [MAX_SAMPLES_PER_EDGE + 4, 0, 0])


def test_a_flood_of_frame_names_is_refused_past_the_bound():
    from povagent.ros.tf_buffer import MAX_FRAMES
    from povagent.ros.transforms import TransformProblem

    b = TransformBuffer()
    for i in range(MAX_FRAMES):
        b.add("map", f"f{i}", 0, yawed(0, 0, 0), static=True)
    with pytest.raises(TransformProblem, match="already holds"):
        b.add("map", "one_more", 0, yawed(0, 0, 0), static=True)

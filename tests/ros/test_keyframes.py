"""The keyframe memory's rules: keep on motion, drop the most covered view when full."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.ros.camera_info import Intrinsics
from povagent.ros.keyframes import Keyframe, KeyframeMemory, MemorySettings, coverage, sample_points

INTRINSICS = Intrinsics(100.0, 100.0, 64.0, 48.0, 128, 96)
#: Columns: the optical axes (x right, y down, z forward) in a body frame (x forward, y left, z up).
BODY_FROM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def frame(x: float, y: float = 0.0, yaw: float = 0.0, stamp: int = 0, depth: np.ndarray | None = None) -> Keyframe:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    pose = np.eye(4)
    pose[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ BODY_FROM_OPTICAL
    pose[:3, 3] = (x, y, 1.0)
    return Keyframe(stamp, np.zeros((96, 128, 3), np.uint8), INTRINSICS.camera(pose), depth, "camera_optical_frame")


def kept(memory: KeyframeMemory) -> list[int]:
    return [f.stamp_ns for f in memory.frames]


def test_the_first_frame_is_always_kept():
    memory = KeyframeMemory()
    memory.offer(frame(0, stamp=1))
    assert kept(memory) == [1]


@pytest.mark.parametrize(("moved", "is_kept"), [(0.4, False), (0.5, False), (0.6, True)])
def test_a_frame_is_kept_when_the_camera_moved_more_than_min_translation(moved, is_kept):
    memory = KeyframeMemory()
    memory.offer(frame(0, stamp=1))
    memory.offer(frame(moved, stamp=2))
    assert kept(memory) == ([1, 2] if is_kept else [1])


@pytest.mark.parametrize(("turned", "is_kept"), [(25.0, False), (35.0, True), (-35.0, True)])
def test_a_frame_is_kept_when_the_camera_turned_more_than_min_rotation(turned, is_kept):
    memory = KeyframeMemory()
    memory.offer(frame(0, stamp=1))
    memory.offer(frame(0, yaw=turned, stamp=2))
    assert kept(memory) == ([1, 2] if is_kept else [1])


def test_motion_is_measured_from_the_last_kept_frame_not_the_last_seen():
    memory = KeyframeMemory()
    for i, x in enumerate([0.0, 0.3, 0.6, 0.9, 1.2]):
        memory.offer(frame(x, stamp=i))
    assert kept(memory) == [0, 2, 4]  # 0.3 and 0.9 are 0.3 m from the frame kept before them


def test_the_thresholds_are_settings():
    memory = KeyframeMemory(MemorySettings(min_translation=0.1, min_rotation=5.0))
    for i, x in enumerate([0.0, 0.15, 0.3]):
        memory.offer(frame(x, stamp=i))
    assert kept(memory) == [0, 1, 2]


def test_when_full_the_view_lying_inside_another_is_dropped():
    memory = KeyframeMemory(MemorySettings(max_frames=3))
    a, b, behind, side = frame(0, stamp=1), frame(0.6, stamp=2), frame(0, yaw=180, stamp=3), frame(0, yaw=90, stamp=4)
    for f in (a, b, behind, side):
        memory.offer(f)
    # b looks the same way from 0.6 m ahead: everything it sees at 2 m is inside a's image
    assert coverage([a, b, behind, side], memory.settings).tolist()[1] == 1.0
    assert kept(memory) == [1, 3, 4]


def test_with_no_view_covered_the_oldest_is_dropped():
    memory = KeyframeMemory(MemorySettings(max_frames=2))
    for i, yaw in enumerate([0, 120, 240]):
        memory.offer(frame(0, yaw=yaw, stamp=i))
    assert coverage(memory.frames, memory.settings).tolist() == [0.0, 0.0]
    assert kept(memory) == [1, 2]


def test_a_new_frame_that_is_the_most_covered_is_itself_dropped_and_still_counts_as_accepted():
    memory = KeyframeMemory(MemorySettings(max_frames=2))
    memory.offer(frame(0, stamp=1))
    memory.offer(frame(0, yaw=180, stamp=2))
    dropped = memory.offer(frame(0.6, stamp=3))
    assert dropped is not None and dropped.stamp_ns == 3 and kept(memory) == [1, 2]
    memory.offer(frame(0.7, stamp=4))  # 0.1 m from the accepted (dropped) frame: not offered again
    assert kept(memory) == [1, 2]


def test_coverage_samples_sit_at_the_depth_image_reading_where_there_is_one():
    depth = np.full((48, 64), 3.0)
    depth[:24] = np.nan  # a hole: the default depth there
    points = sample_points(frame(0, depth=depth), MemorySettings(coverage_depth=2.0))
    ahead = points[:, 0]  # the camera looks along the map's x from x = 0
    assert set(np.round(ahead, 9)) == {2.0, 3.0}
    assert np.all(ahead[: len(ahead) // 2] == 2.0) and np.all(ahead[len(ahead) // 2:] == 3.0)


@pytest.mark.parametrize("bad", [{"max_frames": 0}, {"min_translation": -1.0}, {"coverage_depth": 0.0}, {"grid": (0, 3)}])
def test_settings_out_of_range_are_refused(bad):
    with pytest.raises(ValueError):
        MemorySettings(**bad)

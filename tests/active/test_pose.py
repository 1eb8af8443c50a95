"""Poses: turning right grows the yaw, tilting down grows the horizon (clamped), moves follow the heading."""

from __future__ import annotations

import pytest

from povagent.active.pose import Pose


def test_a_positive_turn_is_to_the_right_as_cam_yaw_grows():
    assert Pose(0, 0.9, 0, 350.0, 30).turned(20).yaw == pytest.approx(10.0)


@pytest.mark.parametrize(("start", "tilt", "after"), [(30, 100, 60), (0, -45, -30), (10, 5, 15)])
def test_a_tilt_is_clamped_to_the_robot_range(start, tilt, after):
    assert Pose(0, 0.9, 0, 0, start).tilted(tilt).horizon == after


def test_forward_follows_the_heading_and_right_is_clockwise_of_it():
    east = Pose(0, 0.9, 0, 90.0, 0)
    assert east.offset(1.0, 0.0) == pytest.approx((1.0, 0.0))
    assert east.offset(0.0, 1.0) == pytest.approx((0.0, -1.0))


def test_a_pose_says_where_it_is_relative_to_the_start():
    start = Pose(0, 0.9, 0, 0.0, 30)
    words = start.moved_to(0.0, 2.0).turned(-90).in_words(start)
    assert "+2.00 m forward" in words and "90 degrees left" in words

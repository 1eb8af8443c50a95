"""Which frame goals are in: the one named, ``map`` when /tf is read, else the odometry's own."""

from __future__ import annotations

from povagent.ros.goal_frame import chosen_goal_frame, goal_frame_at_start, goal_frame_decided


def test_a_named_map_frame_is_the_goal_frame_whatever_else_is_there():
    assert chosen_goal_frame("/odom", reads_tf=True, odom_topic="/odom") == "odom"


def test_with_tf_read_and_no_frame_named_goals_are_in_map():
    assert chosen_goal_frame("", reads_tf=True, odom_topic="/odom") == "map"


def test_without_tf_the_odometry_decides_the_goal_frame():
    assert chosen_goal_frame("", reads_tf=False, odom_topic="/odom") == ""


def test_without_tf_or_odometry_goals_are_in_map():
    assert chosen_goal_frame("", reads_tf=False, odom_topic="") == "map"


def test_the_start_line_names_the_frame_or_how_it_is_decided():
    assert goal_frame_at_start("map", "/odom") == "goals are in the 'map' frame (parameter map_frame sets it)"
    assert goal_frame_at_start("", "/odom").startswith("goals will be in the frame of the first odometry message on /odom")


def test_the_decided_line_names_the_frame_and_the_topic():
    assert goal_frame_decided("odom", "/wheel/odom").startswith("goals are in the 'odom' frame: the frame of the odometry on /wheel/odom")

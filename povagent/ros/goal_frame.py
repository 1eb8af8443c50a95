"""Which frame the node's goals are in, and the line that tells the user.

Goals are points in one fixed frame, the ``map_frame`` parameter. When the user sets it, that is
the frame. When they leave it unset (``""``), the node picks:

* ``map`` when it reads ``/tf`` (a ROS installation provides tf2_msgs): a robot publishing a map
  publishes ``map`` -> ``odom`` there;
* otherwise, with an ``odom_topic``, the frame of the odometry itself: the ``header.frame_id`` of
  the first odometry message (``odom`` on most robots). With the PyPI packages alone no ``/tf``
  is read, so the odometry is the only pose there is, and a goal in its frame is what the robot
  can drive to. The frame is decided when that message comes and is then fixed for the run.

The node prints the frame at start, or that it waits for the first odometry to decide it, and
prints it again when it is decided. Pure: no rclpy.
"""

from __future__ import annotations

#: The frame goals are in when ``/tf`` is read and the user named none.
DEFAULT_MAP_FRAME = "map"


def chosen_goal_frame(map_frame: str, reads_tf: bool, odom_topic: str) -> str:
    """The goal frame fixed at start, or ``""`` when the first odometry message decides it."""
    if map_frame.strip("/ "):
        return map_frame.strip("/ ")
    if reads_tf or not odom_topic:
        return DEFAULT_MAP_FRAME
    return ""


def goal_frame_at_start(goal_frame: str, odom_topic: str) -> str:
    """The line printed at start: the frame goals are in, or how it is decided."""
    if goal_frame:
        return f"goals are in the {goal_frame!r} frame (parameter map_frame sets it)"
    return (f"goals will be in the frame of the first odometry message on {odom_topic} (no /tf is read and "
            "map_frame is unset; set -p map_frame:=FRAME to choose it)")


def goal_frame_decided(goal_frame: str, odom_topic: str) -> str:
    """The line printed when the first odometry message has decided the frame."""
    return f"goals are in the {goal_frame!r} frame: the frame of the odometry on {odom_topic} (map_frame sets another)"


__all__ = ["DEFAULT_MAP_FRAME", "chosen_goal_frame", "goal_frame_at_start", "goal_frame_decided"]

"""Publishing a house tour on a live ROS 2 graph: the robot a test or the example plays to the node.

For each frame, in order: the base's pose (``nav_msgs/Odometry`` on ``/odom``, ``map`` ->
``base_link``, and the same on ``/tf`` when tf2_msgs is installed), the ``CameraInfo``, then the
``rgb8`` image, all stamped with the frame's stamp. The camera mount is published on
``/tf_static`` when tf2_msgs is installed; :func:`mount_parameters` gives it as the node's
``mount_*`` parameters for the PyPI-only stack. The numbers are those :mod:`povagent.ros.tour_bag`
writes, so a bag and a live run carry the same messages.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from povagent.errors import ConfigError
from povagent.ros.extras import ROS_EXTRA, prepare_ros_environment, tf2_messages
from povagent.ros.house_tour import BASE_FRAME, CAMERA_FRAME, MAP_FRAME, HouseTour
from povagent.ros.transforms import RigidTransform

prepare_ros_environment()  # before rclpy's first import
try:
    from geometry_msgs.msg import TransformStamped
    from nav_msgs.msg import Odometry
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.time import Time
    from sensor_msgs.msg import CameraInfo, Image
    from std_msgs.msg import String
except ImportError as _missing:
    raise ConfigError(f"playing a tour needs ROS 2's Python packages ({_missing.name} is missing): {ROS_EXTRA}") from None


def mount_parameters(tour: HouseTour) -> dict[str, Any]:
    """The node's ``mount_*`` parameters carrying the tour's camera mount."""
    m = tour.mount
    return {"mount_parent": BASE_FRAME, "mount_child": CAMERA_FRAME, "mount_transform": [*m.translation, *m.rotation]}


def _stamped_transform(stamp: int, parent: str, child: str, t: RigidTransform) -> Any:
    msg = TransformStamped()
    msg.header.stamp, msg.header.frame_id, msg.child_frame_id = Time(nanoseconds=stamp).to_msg(), parent, child
    msg.transform.translation.x, msg.transform.translation.y, msg.transform.translation.z = t.translation
    msg.transform.rotation.x, msg.transform.rotation.y, msg.transform.rotation.z, msg.transform.rotation.w = t.rotation
    return msg


def odometry(stamp: int, t: RigidTransform) -> Any:
    """The base's pose as ``nav_msgs/Odometry`` (``map`` -> ``base_link``)."""
    msg = Odometry()
    msg.header.stamp, msg.header.frame_id, msg.child_frame_id = Time(nanoseconds=stamp).to_msg(), MAP_FRAME, BASE_FRAME
    p = msg.pose.pose
    p.position.x, p.position.y, p.position.z = t.translation
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = t.rotation
    return msg


def camera_info(tour: HouseTour, stamp: int) -> Any:
    """The tour's calibration as ``CameraInfo`` (``D`` empty: no distortion)."""
    i = tour.intrinsics
    msg = CameraInfo()
    msg.header.stamp, msg.header.frame_id = Time(nanoseconds=stamp).to_msg(), CAMERA_FRAME
    msg.width, msg.height, msg.distortion_model = i.width, i.height, "plumb_bob"
    msg.k = i.k_matrix()
    return msg


def image(rgb: np.ndarray, stamp: int, encoding: str = "rgb8", frame: str = CAMERA_FRAME) -> Any:
    """An RGB array as ``sensor_msgs/Image``."""
    msg = Image()
    msg.header.stamp, msg.header.frame_id = Time(nanoseconds=stamp).to_msg(), frame
    msg.height, msg.width = int(rgb.shape[0]), int(rgb.shape[1])
    msg.encoding, msg.step = encoding, int(rgb.shape[1]) * (rgb.shape[2] if rgb.ndim == 3 else 1)
    msg.data = np.ascontiguousarray(rgb, dtype=np.uint8).tobytes()
    return msg


class TourPlayer:
    """Publishers for a tour on ``node`` (image, camera_info, odom, tf, command)."""

    def __init__(self, node: Any, command_topic: str = "/povagent/command") -> None:
        # deep enough for a whole short tour: a reliable writer drops what its history no longer holds
        reliable = QoSProfile(depth=30, reliability=ReliabilityPolicy.RELIABLE)
        self.node = node
        self.image = node.create_publisher(Image, "/camera/image_raw", reliable)
        self.info = node.create_publisher(CameraInfo, "/camera/camera_info", reliable)
        self.odom = node.create_publisher(Odometry, "/odom", 50)
        self.command = node.create_publisher(String, command_topic, 10)
        self._tf2 = tf2_messages()
        if self._tf2 is not None:
            static = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            self.tf = node.create_publisher(self._tf2.TFMessage, "/tf", 100)
            self.tf_static = node.create_publisher(self._tf2.TFMessage, "/tf_static", static)

    def play(self, tour: HouseTour, after_each: Callable[[int], None] | None = None) -> None:
        """Publish every frame (pose, calibration, image); ``after_each(i)`` after frame ``i``."""
        if self._tf2 is not None:
            first = tour.frames[0].stamp_ns
            self.tf_static.publish(self._tf2.TFMessage(transforms=[_stamped_transform(first, BASE_FRAME, CAMERA_FRAME, tour.mount)]))
        for i, frame in enumerate(tour.frames):
            s = frame.stamp_ns
            self.odom.publish(odometry(s, frame.map_from_base))
            if self._tf2 is not None:
                self.tf.publish(self._tf2.TFMessage(transforms=[_stamped_transform(s, MAP_FRAME, BASE_FRAME, frame.map_from_base)]))
            self.info.publish(camera_info(tour, s))
            self.image.publish(image(frame.rgb, s))
            if after_each is not None:
                after_each(i)

    def say(self, sentence: str) -> None:
        """Publish a command."""
        self.command.publish(String(data=sentence))


__all__ = ["TourPlayer", "camera_info", "image", "mount_parameters", "odometry"]

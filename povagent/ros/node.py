"""The ROS 2 node: camera topics and transforms in, a command in, a goal in the map out.

Topics (parameters give the names; defaults in :data:`DEFAULT_PARAMETERS`):

* in: ``image_topic`` (``sensor_msgs/Image``; a name ending ``/compressed`` takes
  ``CompressedImage``), ``camera_info_topic``, ``depth_topic`` (optional, ``""`` to disable),
  ``tf_topic`` and ``tf_static_topic`` (``tf2_msgs/TFMessage``, when a ROS installation provides
  tf2_msgs), ``odom_topic`` (``nav_msgs/Odometry``, ``""`` to disable), ``~/command``
  (``std_msgs/String``);
* out: ``~/goal`` (``geometry_msgs/PointStamped`` in ``map_frame``), ``/goal_pose``
  (``geometry_msgs/PoseStamped`` at the goal, facing from the chosen keyframe's camera to it:
  what Nav2's ``bt_navigator`` takes; remap it), ``~/result`` (``std_msgs/String``: the JSON of
  :class:`~povagent.ros.result.CommandResult`).

Every message goes to the same :class:`~povagent.ros.session.GroundingSession` the bag replay
uses. The model is never called on the executor: commands go to a bounded queue served by one
worker thread (:mod:`~povagent.ros.command_worker`), so images keep arriving while a command is
answered; a command that has to wait gets a ``queued`` result at once, one that finds the queue
full a ``queue_full`` result, and every command one final result. A malformed message is counted
and logged once per kind. A camera mount given as parameters
(``mount_parent``, ``mount_child``, ``mount_transform`` = x y z qx qy qz qw, a string or an
array: :mod:`~povagent.ros.camera_mount`) stands in for ``/tf_static`` where none is published.
The camera topics are subscribed as :mod:`~povagent.ros.camera_subscriptions` explains; the frame
goals are in is chosen (and printed) as :mod:`~povagent.ros.goal_frame` says. With
``navigate_action`` set (``navigate_to_pose``), each goal goes to Nav2 as that action instead of
``/goal_pose``, its outcome on ``~/result`` (:mod:`~povagent.ros.navigate_action`).
"""

from __future__ import annotations

import math
import threading
from typing import Any

from povagent.errors import ConfigError
from povagent.ros.camera_mount import mount_from_parameter
from povagent.ros.camera_subscriptions import camera_info_profiles, image_profiles, subscribe_camera_stream
from povagent.ros.command_worker import CommandWorker
from povagent.ros.extras import ROS_EXTRA, prepare_ros_environment, tf2_messages
from povagent.ros.goal_frame import chosen_goal_frame, goal_frame_at_start, goal_frame_decided
from povagent.ros.keyframes import DEFAULT_MAX_FRAMES, DEFAULT_MIN_ROTATION, DEFAULT_MIN_TRANSLATION, MemorySettings
from povagent.ros.navigate_action import NavigateToPose, NavigationInterface
from povagent.ros.result import CommandResult
from povagent.ros.session import GroundingSession, Locate
from povagent.ros.tf_buffer import DEFAULT_TOLERANCE_S
from povagent.ros.transforms import TransformProblem

prepare_ros_environment()  # before rclpy's first import
try:
    from geometry_msgs.msg import PointStamped, PoseStamped
    from nav_msgs.msg import Odometry
    from rcl_interfaces.msg import ParameterDescriptor
    from rclpy.exceptions import InvalidParameterTypeException
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.time import Time
    from sensor_msgs.msg import CameraInfo, CompressedImage, Image
    from std_msgs.msg import String
except ImportError as _missing:
    raise ConfigError(f"ros-node needs ROS 2's Python packages ({_missing.name} is missing): {ROS_EXTRA}") from None

#: Seconds ``close()`` waits for the command being answered before the node is destroyed anyway.
CLOSE_TIMEOUT_S = 30.0

#: The node's parameters and their defaults.
DEFAULT_PARAMETERS: dict[str, Any] = {
    "image_topic": "/camera/image_raw",
    "camera_info_topic": "/camera/camera_info",
    "depth_topic": "/camera/depth/image_raw",
    "tf_topic": "/tf",
    "tf_static_topic": "/tf_static",
    "odom_topic": "",
    "map_frame": "",  # unset: povagent.ros.goal_frame chooses
    "min_translation": DEFAULT_MIN_TRANSLATION,
    "min_rotation": DEFAULT_MIN_ROTATION,
    "max_frames": DEFAULT_MAX_FRAMES,
    "transform_tolerance": DEFAULT_TOLERANCE_S,
    "max_queue": 4,
    "reliable_images": False,
    "mount_parent": "base_link",
    "mount_child": "",
    "mount_transform": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
    "navigate_action": "",
}
#: Parameters that take more than one type (``mount_transform``: a string or an array).
DYNAMICALLY_TYPED = frozenset({"mount_transform"})

#: ``~/command``: reliable, and every command kept until the executor takes it: a history of 10
#: dropped all but 10 of a burst before the node saw them; taken, each gets a final result.
COMMAND_QOS = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
#: ``~/result``: reliable, the last 1,000 results kept for a subscriber catching up after a burst
#: (a history, not KEEP_ALL: a slow subscriber must never block the worker's publish).
RESULT_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


class GroundingNode(Node):
    """``povagent`` as a ROS 2 node (see the module docstring); ``close()`` stops its worker.
    ``navigation`` replaces nav2_msgs' ``NavigateToPose`` as the ``navigate_action``'s interface
    (a navigator serving an action of its own)."""

    def __init__(self, locate: Locate, *, name: str = "povagent", context: Any = None, parameter_overrides: list[Any] | None = None,
                 navigation: NavigationInterface | None = None) -> None:
        super().__init__(name, context=context, parameter_overrides=parameter_overrides or [])
        for key, default in DEFAULT_PARAMETERS.items():
            try:
                self.declare_parameter(key, default, ParameterDescriptor(dynamic_typing=key in DYNAMICALLY_TYPED))
            except InvalidParameterTypeException:
                self.destroy_node()
                raise ConfigError(f"ros-node parameters: parameter {key} must be of the type of its default, {default!r}") from None
        p = {key: self.get_parameter(key).value for key in DEFAULT_PARAMETERS}
        try:
            settings = MemorySettings(float(p["min_translation"]), float(p["min_rotation"]), int(p["max_frames"]))
            mount = mount_from_parameter(p["mount_transform"])
            if float(p["transform_tolerance"]) < 0:
                raise ValueError(f"transform_tolerance must be >= 0 seconds, got {p['transform_tolerance']}")
        except (ValueError, TransformProblem) as exc:
            self.destroy_node()
            raise ConfigError(f"ros-node parameters: {exc}") from None
        tf2 = tf2_messages()
        odom_topic = str(p["odom_topic"])
        goal_frame = chosen_goal_frame(str(p["map_frame"]), reads_tf=tf2 is not None, odom_topic=odom_topic)
        self.get_logger().info(goal_frame_at_start(goal_frame, odom_topic))
        self.session = GroundingSession(
            locate,
            map_frame=goal_frame,
            settings=settings,
            tolerance_s=float(p["transform_tolerance"]),
            on_problem=self._log_problem,
            on_goal_frame=lambda frame: self._say(goal_frame_decided(frame, odom_topic)),
        )
        if p["mount_child"]:
            self.session.add_static(str(p["mount_parent"]), str(p["mount_child"]), mount)
        # held while publishing and while closing: no publish can reach a destroyed publisher
        self._publishing = threading.RLock()  # re-entrant: a navigation outcome may publish from inside a publish
        self._closed = False
        self.goal_pub = self.create_publisher(PointStamped, "~/goal", 10)
        self.result_pub = self.create_publisher(String, "~/result", RESULT_QOS)
        # with the action, Nav2 gets the goal from it alone: bt_navigator turns /goal_pose into the same action
        try:
            self.navigate = NavigateToPose(self, str(p["navigate_action"]), self._publish_outcome, navigation) if p["navigate_action"] else None
        except ConfigError:
            self.destroy_node()
            raise
        self.goal_pose_pub = self.create_publisher(PoseStamped, "/goal_pose", 10) if self.navigate is None else None
        images, infos = image_profiles(bool(p["reliable_images"])), camera_info_profiles(bool(p["reliable_images"]))
        image_topic = str(p["image_topic"])
        if image_topic.endswith("/compressed"):
            subscribe_camera_stream(self, CompressedImage, image_topic, self._guarded(self.session.on_compressed_image), images)
        else:
            subscribe_camera_stream(self, Image, image_topic, self._guarded(self.session.on_image), images)
        subscribe_camera_stream(self, CameraInfo, str(p["camera_info_topic"]), self._guarded(self.session.on_camera_info), infos, images=False)
        if p["depth_topic"]:
            subscribe_camera_stream(self, Image, str(p["depth_topic"]), self._guarded(self.session.on_depth), images)
        if odom_topic:
            self.create_subscription(Odometry, odom_topic, self._guarded(self.session.on_odometry), 50)
        if tf2 is not None:
            static_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            self.create_subscription(tf2.TFMessage, str(p["tf_topic"]), self._guarded(self.session.on_tf), 100)
            self.create_subscription(tf2.TFMessage, str(p["tf_static_topic"]), self._guarded(lambda m: self.session.on_tf(m, static=True)), static_qos)
        else:
            self.get_logger().warning(
                "tf2_msgs is not installed (it has no PyPI wheel): /tf and /tf_static are not read; "
                "poses come from odom_topic and the mount_* parameters"
            )
        self.commands = CommandWorker(self.session.answer, self.publish_result, map_frame=self.session.map_frame,
                                      max_queue=int(p["max_queue"]), log_bug=self.get_logger().error)
        self.create_subscription(String, "~/command", lambda msg: self.commands.submit(str(msg.data)), COMMAND_QOS)

    # -- messages -----------------------------------------------------------------------------
    def _guarded(self, take: Any) -> Any:
        def callback(msg: Any) -> None:
            try:
                take(msg)
            except Exception as exc:
                self.session.problem("unexpected", f"{type(exc).__name__}: {exc}")
        return callback

    def _say(self, line: str) -> None:
        self.get_logger().info(line)

    def _log_problem(self, kind: str, message: str, first: bool) -> None:
        if first:
            self.get_logger().warning(f"malformed input ({kind}): {message}; counted, further {kind} problems are not logged")

    # -- results ------------------------------------------------------------------------------
    def publish_result(self, result: CommandResult) -> None:
        """Publish ``~/result`` and, with a goal, ``~/goal`` and ``/goal_pose`` (nothing once closed)."""
        with self._publishing:
            if not self._closed:
                self._publish(result)

    def _publish(self, result: CommandResult) -> None:
        if result.goal is not None and result.frame_stamp_ns is not None:
            stamp = Time(nanoseconds=result.frame_stamp_ns).to_msg()
            point = PointStamped()
            point.header.stamp, point.header.frame_id = stamp, result.map_frame
            point.point.x, point.point.y, point.point.z = result.goal
            pose = PoseStamped()
            pose.header = point.header
            pose.pose.position = point.point
            yaw = result.facing_yaw() or 0.0
            pose.pose.orientation.z, pose.pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
            self.goal_pub.publish(point)
            if self.navigate is not None:
                result = result.model_copy(update={"navigation": self.navigate.send(pose, result)})
            else:
                self.goal_pose_pub.publish(pose)  # type: ignore[union-attr]
        self.result_pub.publish(String(data=result.model_dump_json()))

    def _publish_outcome(self, result: CommandResult) -> None:
        """A navigation's outcome: ``~/result`` alone (from the action client's futures, on the executor)."""
        with self._publishing:
            if not self._closed:
                self.result_pub.publish(String(data=result.model_dump_json()))

    def destroy_node(self) -> None:
        """Destroy the navigation action's client first (rclpy leaves waitables to their owner), then the node."""
        navigate = getattr(self, "navigate", None)  # absent when a parameter was refused
        if navigate is not None:
            navigate.destroy()
        super().destroy_node()

    @property
    def answering(self) -> bool:
        """Whether the worker is answering a command now."""
        return self.commands.answering

    def close(self) -> None:
        """Stop the worker (after the command it is answering), join it, then destroy the node.

        Call it after the executor spinning this node has stopped (see
        :class:`~povagent.ros.spinning.BackgroundSpin`) and before the context shuts down. A
        worker still answering after ``CLOSE_TIMEOUT_S`` is left to finish on its own: its result
        is not published (the publishers are gone), and a warning says so.
        """
        self.commands.close(timeout=CLOSE_TIMEOUT_S)
        if self.commands.answering:
            self.get_logger().warning(f"a command was still being answered after {CLOSE_TIMEOUT_S:g} s; its result is dropped")
        with self._publishing:
            self._closed = True
            self.destroy_node()


__all__ = ["COMMAND_QOS", "DEFAULT_PARAMETERS", "RESULT_QOS", "GroundingNode"]

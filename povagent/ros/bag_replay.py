"""Bag replay: a recorded ROS 2 bag through the same session as the live node.

A bag (a rosbag2 folder, sqlite3 or mcap storage; read with ``rosbags``, no rclpy) is read in
log-time order and each message on the chosen topics goes to the
:class:`~povagent.ros.session.GroundingSession` call the node's subscription makes for it; then
the command is answered. Messages are deserialized with the definitions the bag carries, or
ROS 2 Jazzy's standard ones when it carries none. A bag that cannot be opened is one
:class:`~povagent.errors.ConfigError` naming it, on one line whatever the reader said; a message
that cannot be deserialized is counted (``deserialize``) like any malformed message, and the
replay goes on. So is a message of another type than its topic takes (a ``std_msgs/String``
under the camera_info topic), or whose definition, carried in the bag under the right name, lacks
a field read (``message_type``): it is never handed on.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from povagent.errors import ConfigError
from povagent.ros.extras import require_rosbags
from povagent.ros.session import GroundingSession

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
ODOMETRY = "nav_msgs/msg/Odometry"
#: The longest reader message quoted in the one-line error of a bag that cannot be opened.
MAX_REASON_CHARS = 300


@dataclass(frozen=True)
class ReplayTopics:
    """The topics read from the bag (``""`` leaves one out)."""

    image: str = "/camera/image_raw"
    camera_info: str = "/camera/camera_info"
    depth: str = "/camera/depth/image_raw"
    tf: str = "/tf"
    tf_static: str = "/tf_static"
    odom: str = "/odom"


def replay_bag(bag: str | os.PathLike, session: GroundingSession, topics: ReplayTopics | None = None) -> int:
    """Feed ``bag``'s messages to ``session``; returns how many messages were read."""
    highlevel = require_rosbags("ros-replay")
    from rosbags.typesys import Stores, get_typestore

    topics = topics or ReplayTopics()
    path = Path(bag)
    if not path.exists():
        raise ConfigError(f"{path}: no such bag")
    # topic -> (the message types it takes, what takes one)
    takes: dict[str, tuple[tuple[str, ...], Callable[[Any, str], None]]] = {}
    if topics.image:
        takes[topics.image] = ((IMAGE, COMPRESSED), lambda m, t: session.on_compressed_image(m) if t == COMPRESSED else session.on_image(m))
    if topics.camera_info:
        takes[topics.camera_info] = ((CAMERA_INFO,), lambda m, t: session.on_camera_info(m))
    if topics.depth:
        takes[topics.depth] = ((IMAGE,), lambda m, t: session.on_depth(m))
    if topics.tf:
        takes[topics.tf] = ((TF_MESSAGE,), lambda m, t: session.on_tf(m))
    if topics.tf_static:
        takes[topics.tf_static] = ((TF_MESSAGE,), lambda m, t: session.on_tf(m, static=True))
    if topics.odom:
        takes[topics.odom] = ((ODOMETRY,), lambda m, t: session.on_odometry(m))
    count = 0
    try:
        reader = highlevel.AnyReader([path], default_typestore=get_typestore(Stores.ROS2_JAZZY))
        reader.open()
    except Exception as exc:
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())  # a YAML error spans lines: one line
        if len(reason) > MAX_REASON_CHARS:
            reason = reason[:MAX_REASON_CHARS] + "..."
        raise ConfigError(f"{path}: cannot open the bag: {reason}") from None
    try:
        connections = [c for c in reader.connections if c.topic in takes]
        if not any(c.topic == topics.image for c in connections):
            found = ", ".join(sorted({c.topic for c in reader.connections})) or "none"
            raise ConfigError(f"{path}: no image topic {topics.image!r} in the bag (topics: {found}); give --image-topic")
        for connection, _, raw in reader.messages(connections=connections):
            count += 1
            types, take = takes[connection.topic]
            if connection.msgtype not in types:
                session.problem("message_type", f"{connection.topic}: a {connection.msgtype} message, but the topic takes {' or '.join(types)}")
                continue
            try:
                msg = reader.deserialize(raw, connection.msgtype)
            except Exception as exc:
                session.problem("deserialize", f"{connection.topic}: {type(exc).__name__}: {exc}")
                continue
            try:
                take(msg, connection.msgtype)
            except (AttributeError, TypeError) as exc:  # the bag's own definition of the type differs from the standard one
                session.problem("message_type", f"{connection.topic}: the bag's {connection.msgtype} is not the standard one ({type(exc).__name__}: {exc})")
    finally:
        reader.close()
    session.flush()
    return count


__all__ = ["CAMERA_INFO", "COMPRESSED", "IMAGE", "ODOMETRY", "TF_MESSAGE", "ReplayTopics", "replay_bag"]

"""How the node listens to a camera: the QoS of its image, depth and calibration subscriptions, and why.

Two kinds of publisher must both be heard at the defaults:

* a **camera driver**: sensor-data QoS (best effort, volatile), publishing all the time;
* a **script publishing once** (a test, a tour player, a one-off ``ros2 topic pub``): reliable,
  its ``camera_info`` often reliable and transient local (latched), sent once, maybe before the
  node started.

DDS matches a subscription to a publisher only when the publisher offers at least what the
subscription requests: a ``RELIABLE`` subscription does not match a ``BEST_EFFORT`` publisher (a
``BEST_EFFORT`` one matches both), and a ``TRANSIENT_LOCAL`` subscription does not match a
``VOLATILE`` publisher (a ``VOLATILE`` one matches both but receives no history). So no single
profile hears both kinds fully: best effort hears a driver but takes a reliable script's large
images without retransmission (a burst loses some), reliable never hears a best-effort driver.
The node therefore subscribes each stream twice, to the same session:

* **images and depth**: best effort, keeping 10 (every publisher; a driver's images come this
  way) and reliable, keeping 30 (reliable publishers only; their images come this way, resent when
  lost, a script's burst held until the executor takes it). From a
  reliable publisher both copies come: :class:`FirstCopy` passes the first copy of each image
  (same stamp, frame, encoding or format, size) and drops the second before it is decoded;
* **camera_info**: best effort and volatile (every publisher, live), and reliable and transient
  local with a history of one (a latched calibration reaches the node even when it was published
  before the node started). A second copy of a calibration sets the same intrinsics again.

A reliable subscription facing a best-effort driver is an expected mismatch, not a fault: those
subscriptions log no "incompatible QoS" warning (the driver's own publisher may log one line per
topic when the node starts; a subscription made only once a reliable publisher shows up would
spare that line but miss the start of a script's burst, which is what the reliable one is for). ``reliable_images:=true`` keeps only the
reliable subscriptions (no second copies; a best-effort driver is then not heard). Images that arrive before their calibration wait for it
(:mod:`~povagent.ros.session`), so the order of the two topics does not matter.
"""

from __future__ import annotations

import threading
from collections import deque
from typing import Any, Callable

from povagent.errors import ConfigError
from povagent.ros.extras import ROS_EXTRA, prepare_ros_environment

prepare_ros_environment()  # before rclpy's first import
try:
    from rclpy.event_handler import SubscriptionEventCallbacks
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
except ImportError as _missing:
    raise ConfigError(f"ros-node needs ROS 2's Python packages ({_missing.name} is missing): {ROS_EXTRA}") from None

#: Images the best-effort subscription keeps until the executor takes them (a driver sends more soon).
IMAGE_DEPTH = 10
#: Images the reliable subscription keeps: a script's whole burst (a short tour), since a reliable
#: reader that keeps the last N drops the oldest when the executor falls behind, and nobody resends it.
RELIABLE_DEPTH = 30
#: Image identities remembered to drop second copies (two subscriptions deliver within moments).
REMEMBERED_IMAGES = 64


def _profile(reliability: ReliabilityPolicy, depth: int, durability: DurabilityPolicy = DurabilityPolicy.VOLATILE) -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability, durability=durability)


def image_profiles(reliable_only: bool) -> list[QoSProfile]:
    """The profiles an image or depth topic is subscribed with (see the module docstring)."""
    reliable = _profile(ReliabilityPolicy.RELIABLE, RELIABLE_DEPTH)
    return [reliable] if reliable_only else [_profile(ReliabilityPolicy.BEST_EFFORT, IMAGE_DEPTH), reliable]


def camera_info_profiles(reliable_only: bool) -> list[QoSProfile]:
    """The profiles ``camera_info`` is subscribed with: live from every publisher, latched from any that latches."""
    latched = _profile(ReliabilityPolicy.RELIABLE, 1, DurabilityPolicy.TRANSIENT_LOCAL)
    if reliable_only:
        return [_profile(ReliabilityPolicy.RELIABLE, RELIABLE_DEPTH), latched]
    return [_profile(ReliabilityPolicy.BEST_EFFORT, IMAGE_DEPTH), latched]


def quiet_mismatch() -> SubscriptionEventCallbacks:
    """Event callbacks that take an incompatible-QoS event silently (rclpy's default logs a warning)."""
    return SubscriptionEventCallbacks(incompatible_qos=lambda event: None)


def subscribe_camera_stream(node: Any, msg_type: Any, topic: str, take: Callable[[Any], None], profiles: list[QoSProfile], *, images: bool = True) -> list[Any]:
    """Subscribe ``topic`` once per profile; the copies of one image reach ``take`` once
    (``images=False`` for ``camera_info``, whose copies are harmless)."""
    if images and len(profiles) > 1:
        take = FirstCopy(take)
    return [node.create_subscription(msg_type, topic, take, qos, event_callbacks=quiet_mismatch()) for qos in profiles]


class FirstCopy:
    """Passes the first copy of each image to ``take``; a copy with the same identity (stamp,
    frame, encoding or format, size) seen among the last :data:`REMEMBERED_IMAGES` is dropped.
    Thread-safe: the two subscriptions may deliver on two executor threads at once."""

    def __init__(self, take: Callable[[Any], None], remembered: int = REMEMBERED_IMAGES) -> None:
        self.take = take
        self._order: deque[tuple[Any, ...]] = deque()
        self._seen: set[tuple[Any, ...]] = set()
        self._remembered = remembered
        self._lock = threading.Lock()

    @staticmethod
    def identity(msg: Any) -> tuple[Any, ...]:
        """What makes two messages the same image: header, encoding or format, size in bytes."""
        stamp = msg.header.stamp
        kind = getattr(msg, "encoding", None) or getattr(msg, "format", "")
        return (int(stamp.sec), int(stamp.nanosec), str(msg.header.frame_id), str(kind),
                int(getattr(msg, "width", 0)), int(getattr(msg, "height", 0)), len(msg.data))

    def __call__(self, msg: Any) -> None:
        key = self.identity(msg)
        with self._lock:
            if key in self._seen:
                return
            self._seen.add(key)
            self._order.append(key)
            if len(self._order) > self._remembered:
                self._seen.discard(self._order.popleft())
        self.take(msg)


__all__ = [
    "IMAGE_DEPTH",
    "RELIABLE_DEPTH",
    "REMEMBERED_IMAGES",
    "FirstCopy",
    "camera_info_profiles",
    "image_profiles",
    "quiet_mismatch",
    "subscribe_camera_stream",
]

"""The one code path the node and the bag replay share: messages in, keyframes kept, commands answered.

:class:`GroundingSession` takes messages by kind (``on_image``, ``on_compressed_image``,
``on_depth``, ``on_camera_info``, ``on_tf``, ``on_odometry``) and a command (:meth:`answer`).
The node calls these from its subscriptions, the replay from a bag's messages in log-time order:
the same calls on the same messages give the same memory and the same goal.

An image becomes a keyframe candidate once it has a calibration (the newest ``CameraInfo``), a
pose (``map_frame`` to the image's ``frame_id`` at its stamp, :mod:`~povagent.ros.tf_buffer`) and
optionally a depth image with the same stamp received before it. An image whose transform has not
arrived yet waits in a bounded queue (``max_pending``) and is retried as transforms come; once
transforms newer than its stamp by more than the tolerance exist and it still has no pose, it is
dropped as ``missing_transform``. An image that arrives before any usable ``CameraInfo`` (a
calibration published once, or on its own topic a moment after the image) waits too, in a bounded
queue of its own (``max_pending``; the oldest is dropped as ``no_camera_info`` when it is full),
and goes on with the first calibration that comes.

``map_frame=""`` leaves the goal frame to the first odometry message: its ``header.frame_id``
becomes the frame (:mod:`~povagent.ros.goal_frame` says when the node does this) and
``on_goal_frame`` is told; until then images wait for it as for a transform.

A malformed message is counted by kind (:attr:`problems`) and reported through ``on_problem``
with ``first=True`` the first time a kind is seen, so a node logs each kind once; nothing raised
by a message reaches the caller. Thread-safe: messages may come on one thread while a command is
answered on another (the answer works on a snapshot of the memory).
"""

from __future__ import annotations

import threading
import time
from collections import Counter, deque
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from povagent.agent.localization import Localization
from povagent.agent.shown_frame import ShownFrame
from povagent.errors import BadInputError, NoAnswerError, UnparseableAnswerError
from povagent.geometry.goals import PinholeCamera
from povagent.ros.camera_info import CameraProblem, Intrinsics, intrinsics_from_info
from povagent.ros.image_messages import ImageProblem, compressed_to_rgb, depth_to_metres, image_to_rgb
from povagent.ros.keyframes import Keyframe, KeyframeMemory, MemorySettings
from povagent.ros.result import CommandResult, CommandStatus
from povagent.ros.tf_buffer import DEFAULT_TOLERANCE_S, PoseUnavailable, StampProblem, TransformBuffer, stamp_ns
from povagent.ros.transforms import RigidTransform, TransformProblem, pose_convention

#: What answers a command: the agent's ``locate`` over the memory's frames, cameras and depths.
Locate = Callable[[str, Sequence[ShownFrame], Sequence[PinholeCamera], Sequence["np.ndarray | None"]], Localization]
#: Called with (kind, message, first) for every malformed message.
ProblemSink = Callable[[str, str, bool], None]
#: Called with the goal frame once the first odometry message has decided it.
GoalFrameSink = Callable[[str], None]

DEFAULT_MAX_PENDING = 16
#: The longest command answered (characters); a longer one is ``bad_input``, not sent to a model.
MAX_COMMAND_CHARS = 2_000


@dataclass
class _Pending:
    stamp: int
    frame_id: str
    rgb: np.ndarray
    intrinsics: Intrinsics
    depth: np.ndarray | None


class GroundingSession:
    """Keyframe memory fed by ROS messages, answering commands with one ``locate`` function."""

    def __init__(
        self,
        locate: Locate,
        *,
        map_frame: str = "map",
        memory: KeyframeMemory | None = None,
        settings: MemorySettings | None = None,
        tolerance_s: float = DEFAULT_TOLERANCE_S,
        max_pending: int = DEFAULT_MAX_PENDING,
        on_problem: ProblemSink | None = None,
        on_goal_frame: GoalFrameSink | None = None,
    ) -> None:
        self.locate = locate
        #: the frame goals are in; ``""`` until the first odometry message decides it
        self.map_frame = map_frame.lstrip("/")
        self._on_goal_frame = on_goal_frame
        self.memory = memory if memory is not None else KeyframeMemory(settings)
        self.transforms = TransformBuffer(tolerance_s=tolerance_s)
        self.problems: Counter[str] = Counter()
        self.images_seen = 0
        self._on_problem = on_problem
        self._intrinsics: Intrinsics | None = None
        self._depths: deque[tuple[int, np.ndarray]] = deque(maxlen=8)
        self._pending: deque[_Pending] = deque()
        self._uncalibrated: deque[tuple[int, str, np.ndarray]] = deque()
        self._max_pending = max_pending
        self._lock = threading.RLock()

    @property
    def calibrated(self) -> bool:
        """Whether a usable ``CameraInfo`` has arrived (images before it wait for it, at most ``max_pending``)."""
        return self._intrinsics is not None

    # -- messages ---------------------------------------------------------------------------
    def problem(self, kind: str, message: str) -> None:
        """Count a malformed message of ``kind`` and report it (``first`` the first time)."""
        with self._lock:
            self.problems[kind] += 1
            first = self.problems[kind] == 1
        if self._on_problem is not None:
            self._on_problem(kind, message, first)

    def on_camera_info(self, msg: Any) -> None:
        """Take the newest calibration; images that came before any go on with it."""
        try:
            intrinsics = intrinsics_from_info(msg)
        except CameraProblem as exc:
            self.problem(exc.kind, str(exc))
            return
        with self._lock:
            self._intrinsics = intrinsics
            waiting, self._uncalibrated = list(self._uncalibrated), deque()
        for stamp, frame_id, rgb in waiting:
            self._admit(stamp, frame_id, rgb, intrinsics)

    def on_image(self, msg: Any) -> None:
        """An RGB ``sensor_msgs/Image``."""
        self._take_image(msg, image_to_rgb)

    def on_compressed_image(self, msg: Any) -> None:
        """A ``sensor_msgs/CompressedImage`` (JPEG or PNG)."""
        self._take_image(msg, compressed_to_rgb)

    def on_depth(self, msg: Any) -> None:
        """A depth ``sensor_msgs/Image``, kept for the colour image with the same stamp."""
        try:
            stamp = stamp_ns(msg.header.stamp)
            metres = depth_to_metres(msg)
        except (ImageProblem, StampProblem) as exc:
            self.problem(f"depth_{exc.kind}", f"depth: {exc}")
            return
        with self._lock:
            self._depths.append((stamp, metres))

    def on_tf(self, msg: Any, static: bool = False) -> None:
        """A ``tf2_msgs/TFMessage`` from ``/tf`` or (``static``) ``/tf_static``."""
        try:
            with self._lock:
                self.transforms.add_message(msg, static=static)
        except TransformProblem as exc:
            self.problem("transform", str(exc))
            return
        except StampProblem as exc:
            self.problem(exc.kind, f"transform: {exc}")
            return
        self._retry_pending()

    def on_odometry(self, msg: Any) -> None:
        """A ``nav_msgs/Odometry``: the robot's pose as one more edge of the tree (and, with no
        goal frame given, the frame goals are in)."""
        decided = ""
        try:
            with self._lock:
                self.transforms.add_odometry(msg)
                if not self.map_frame:
                    self.map_frame = decided = str(msg.header.frame_id).strip("/ ")
        except TransformProblem as exc:
            self.problem("transform", str(exc))
            return
        except StampProblem as exc:
            self.problem(exc.kind, f"odometry: {exc}")
            return
        if decided and self._on_goal_frame is not None:
            self._on_goal_frame(decided)
        self._retry_pending()

    def add_static(self, parent: str, child: str, transform: RigidTransform) -> None:
        """A fixed transform given by configuration (a camera mount, when no ``/tf_static`` carries it)."""
        with self._lock:
            self.transforms.add(parent, child, 0, transform, static=True)

    def _take_image(self, msg: Any, decode: Callable[[Any], np.ndarray]) -> None:
        with self._lock:
            self.images_seen += 1
        try:
            stamp = stamp_ns(msg.header.stamp)
            rgb = decode(msg)
        except (ImageProblem, StampProblem) as exc:
            self.problem(exc.kind, str(exc))
            return
        frame_id = str(msg.header.frame_id).lstrip("/")
        uncalibrated: list[tuple[int, str, np.ndarray]] = []
        with self._lock:
            intrinsics = self._intrinsics
            if intrinsics is None:
                self._uncalibrated.append((stamp, frame_id, rgb))
                while len(self._uncalibrated) > self._max_pending:
                    uncalibrated.append(self._uncalibrated.popleft())
        for s, f, _ in uncalibrated:
            self.problem("no_camera_info", f"image at {s / 1e9:.3f} s in {f!r}: no usable camera_info came while {self._max_pending} newer images waited")
        if intrinsics is not None:
            self._admit(stamp, frame_id, rgb, intrinsics)

    def _admit(self, stamp: int, frame_id: str, rgb: np.ndarray, intrinsics: Intrinsics) -> None:
        """An image with its calibration: to the queue of images waiting for their pose."""
        if (rgb.shape[1], rgb.shape[0]) != (intrinsics.width, intrinsics.height):
            self.problem("size_mismatch", f"image of {rgb.shape[1]}x{rgb.shape[0]} but camera_info says {intrinsics.width}x{intrinsics.height}")
            return
        overflow: list[_Pending] = []
        with self._lock:
            depth = next((d for s, d in self._depths if s == stamp), None)
            self._pending.append(_Pending(stamp, frame_id, rgb, intrinsics, depth))
            while len(self._pending) > self._max_pending:
                overflow.append(self._pending.popleft())
        for dropped in overflow:
            self.problem("missing_transform", f"image at {dropped.stamp / 1e9:.3f} s in {dropped.frame_id!r}: waited too long for its transform")
        self._retry_pending()

    def _retry_pending(self) -> None:
        failures: list[str] = []
        with self._lock:
            if not self.map_frame:
                return  # no goal frame yet: every image waits for the first odometry
            still: deque[_Pending] = deque()
            newest = self.transforms.newest_stamp()
            for p in self._pending:
                try:
                    pose = self.transforms.lookup(self.map_frame, p.frame_id, p.stamp)
                except PoseUnavailable as exc:
                    if newest is not None and newest - p.stamp > self.transforms.tolerance_ns:
                        failures.append(f"image at {p.stamp / 1e9:.3f} s in {p.frame_id!r}: {exc}")
                    else:
                        still.append(p)  # its transform may still come
                    continue
                try:
                    camera = p.intrinsics.camera(pose, pose_convention(p.frame_id))
                except ValueError as exc:
                    failures.append(f"image at {p.stamp / 1e9:.3f} s: unusable pose: {exc}")
                    continue
                self.memory.offer(Keyframe(p.stamp, p.rgb, camera, p.depth, p.frame_id))
            self._pending = still
        for message in failures:
            self.problem("missing_transform", message)

    def flush(self) -> None:
        """Give up on images still waiting for a transform (the end of a bag), counting them."""
        self._retry_pending()
        with self._lock:
            left, self._pending = list(self._pending), deque()
            uncalibrated, self._uncalibrated = list(self._uncalibrated), deque()
        for stamp, frame_id, _ in uncalibrated:
            self.problem("no_camera_info", f"image at {stamp / 1e9:.3f} s in {frame_id!r}: no usable camera_info ever came")
        for p in left:
            self.problem("missing_transform", f"image at {p.stamp / 1e9:.3f} s in {p.frame_id!r}: no transform to {self.map_frame!r} ever came")

    # -- commands ---------------------------------------------------------------------------
    def snapshot(self) -> list[Keyframe]:
        """The kept frames now, in memory order."""
        with self._lock:
            return list(self.memory.frames)

    def answer(self, command: str) -> CommandResult:
        """Answer one command over the memory as it is now (blocking: call it off the executor)."""
        started = time.monotonic()
        frames = self.snapshot()
        with self._lock:
            health = {"images": self.images_seen, "malformed": dict(self.problems)}
        base = {"command": command, "map_frame": self.map_frame, "keyframes": len(frames), **health}
        if not command.strip():
            return CommandResult(status=CommandStatus.EMPTY_COMMAND, reason="the command is empty", **base)
        if len(command) > MAX_COMMAND_CHARS:
            return CommandResult(status=CommandStatus.BAD_INPUT, reason=f"the command is {len(command):,} characters long (at most {MAX_COMMAND_CHARS:,})",
                                 **{**base, "command": command[:200] + "..."})
        if not frames:
            return CommandResult(
                status=CommandStatus.NO_KEYFRAMES, reason="no frame has been kept yet (images, camera_info and transforms are all needed)", **base
            )
        try:
            # each keyframe's shown frame: what an earlier command computed of it is reused
            loc = self.locate(command, [f.shown for f in frames], [f.camera for f in frames], [f.depth for f in frames])
        except UnparseableAnswerError as exc:
            status, reason = CommandStatus.UNPARSEABLE, str(exc)
        except NoAnswerError as exc:
            status, reason = CommandStatus.NO_ANSWER, str(exc)
        except BadInputError as exc:
            status, reason = CommandStatus.BAD_INPUT, str(exc)
        else:
            return self._result(base, frames, loc, time.monotonic() - started)
        return CommandResult(status=status, reason=reason, latency_s=time.monotonic() - started, **base)

    def _result(self, base: dict[str, Any], frames: list[Keyframe], loc: Localization, latency: float) -> CommandResult:
        chosen = frames[loc.frame_index]
        goal = None if loc.goal is None else tuple(float(v) for v in loc.goal.point)
        return CommandResult(
            status=CommandStatus.OK if goal is not None else CommandStatus.NO_GOAL,
            reason=(loc.reason or "") if goal is not None else (loc.goal_error or "no 3D goal"),
            frame_index=loc.frame_index,
            frame_stamp_ns=chosen.stamp_ns,
            frame_id=chosen.frame_id,
            pixel=(float(loc.pixel[0]), float(loc.pixel[1])),
            goal=goal,
            goal_method=None if loc.goal is None else loc.goal.method,
            viewpoint=tuple(float(v) for v in chosen.camera.position),
            latency_s=latency,
            **base,
        )


def agent_locate(agent: Any) -> Locate:
    """The :data:`Locate` of a :class:`~povagent.agent.grounding_agent.GroundingAgent`: the
    memory's frames, their cameras and (where every frame has one) their depth images."""

    def locate(sentence: str, frames: Sequence[ShownFrame], cameras: Sequence[PinholeCamera], depths: Sequence[np.ndarray | None]) -> Localization:
        given = list(depths) if any(d is not None for d in depths) else None
        return agent.locate(sentence, list(frames), cameras=list(cameras), depths=given)

    return locate


__all__ = ["DEFAULT_MAX_PENDING", "MAX_COMMAND_CHARS", "GoalFrameSink", "GroundingSession", "Locate", "ProblemSink", "agent_locate"]

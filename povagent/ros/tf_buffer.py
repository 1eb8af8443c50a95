"""The transform tree from ``/tf``, ``/tf_static`` and ``nav_msgs/Odometry``, and the camera's
pose in the map at an image's stamp.

Each ``TransformStamped`` is an edge of a tree (a child has one parent, as in tf2); an
``Odometry`` is the same edge from ``header.frame_id`` to ``child_frame_id``. Static edges hold
for every time. Dynamic edges keep their recent samples; the pose at stamp ``t`` is interpolated
between the two samples nearest ``t`` (linear translation, spherical rotation) when they are on
either side of it, and is the nearest sample itself otherwise. The rule that refuses: a pose is
:class:`PoseUnavailable` when the nearest sample of any edge on the chain is more than
``tolerance_s`` from ``t`` (a gap in the data or a stamp far from any transform), or when no
chain joins the two frames. Nothing is extrapolated.

Pure: stamps are integers of nanoseconds; no clock is read. A stamp is a time since the epoch,
as ``builtin_interfaces/Time`` means it: negative seconds, or nanoseconds outside a second, are
a :class:`StampProblem` (malformed input, counted like any other), never a stamp.
"""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from povagent.ros.transforms import RigidTransform, TransformProblem, interpolate

#: Default largest distance (seconds) between an image's stamp and the nearest transform used.
DEFAULT_TOLERANCE_S = 0.2
#: Default span of dynamic samples kept per edge (seconds before the newest).
DEFAULT_CACHE_S = 30.0
#: At most this many samples per edge (a 1 kHz transform for 10 s) and this many frames in the
#: tree: a flood of transforms, or of frame names, must not grow the buffer without bound.
MAX_SAMPLES_PER_EDGE = 10_000
MAX_FRAMES = 1_000


class PoseUnavailable(ValueError):
    """No pose for a frame at a stamp; ``kind`` is the counter it goes to (``missing_transform``)."""

    kind = "missing_transform"


class StampProblem(ValueError):
    """A header stamp that is no time (see the module docstring); ``kind`` is its counter."""

    kind = "stamp"


def stamp_ns(stamp: Any) -> int:
    """A ``builtin_interfaces/Time`` as integer nanoseconds; :class:`StampProblem` when it is no time."""
    sec, nanosec = int(stamp.sec), int(stamp.nanosec)
    if sec < 0 or not 0 <= nanosec < 1_000_000_000:
        raise StampProblem(f"header stamp {sec} s {nanosec} ns is not a time (seconds must be >= 0, nanoseconds 0-999999999)")
    return sec * 1_000_000_000 + nanosec


def _clean(frame: str) -> str:
    # tf2 drops a leading slash ("/map" and "map" are the same frame)
    return str(frame).lstrip("/")


@dataclass
class _Edge:
    parent: str
    static: RigidTransform | None = None
    times: list[int] = field(default_factory=list)
    samples: deque[RigidTransform] = field(default_factory=deque)


class TransformBuffer:
    """Edges from transform messages; :meth:`lookup` gives ``T_target_source`` at a stamp."""

    def __init__(self, tolerance_s: float = DEFAULT_TOLERANCE_S, cache_s: float = DEFAULT_CACHE_S) -> None:
        if not tolerance_s >= 0 or not cache_s > 0:
            raise ValueError("tolerance_s must be >= 0 and cache_s > 0 (seconds)")
        self.tolerance_ns = int(round(tolerance_s * 1e9))
        self.cache_ns = int(round(cache_s * 1e9))
        self._edges: dict[str, _Edge] = {}  # by child frame

    def add(self, parent: str, child: str, stamp: int, transform: RigidTransform, static: bool = False) -> None:
        """Add one edge sample (``transform`` is the child's pose in the parent)."""
        parent, child = _clean(parent), _clean(child)
        if not parent or not child or parent == child:
            raise TransformProblem(f"transform from {parent!r} to {child!r}: frames must be named and differ")
        edge = self._edges.get(child)
        if edge is None and len(self._edges) >= MAX_FRAMES:
            raise TransformProblem(f"transform to {child!r}: the tree already holds {MAX_FRAMES} frames")
        if edge is None or edge.parent != parent:
            # tf2's rule: a child has one parent; the newest message says which
            edge = self._edges[child] = _Edge(parent)
        if static:
            edge.static = transform
            return
        at = bisect.bisect_left(edge.times, stamp)
        if at < len(edge.times) and edge.times[at] == stamp:
            edge.samples[at] = transform  # the same stamp again: the newer message wins
        else:
            edge.times.insert(at, stamp)
            edge.samples.insert(at, transform)
        while edge.times and (edge.times[-1] - edge.times[0] > self.cache_ns or len(edge.times) > MAX_SAMPLES_PER_EDGE):
            edge.times.pop(0)
            edge.samples.popleft()

    def add_message(self, msg: Any, static: bool = False) -> int:
        """Add every ``TransformStamped`` of a ``tf2_msgs/TFMessage``; returns how many.

        A transform with NaN is :class:`TransformProblem` and none of the message is added."""
        checked = [
            (
                t.header.frame_id,
                t.child_frame_id,
                stamp_ns(t.header.stamp),
                RigidTransform.from_message(t.transform, f"transform {t.header.frame_id} -> {t.child_frame_id}"),
            )
            for t in msg.transforms
        ]
        for parent, child, stamp, transform in checked:
            self.add(parent, child, stamp, transform, static)
        return len(checked)

    def add_odometry(self, msg: Any) -> None:
        """Add a ``nav_msgs/Odometry``: the pose of ``child_frame_id`` in ``header.frame_id``."""
        what = f"odometry {msg.header.frame_id} -> {msg.child_frame_id}"
        self.add(msg.header.frame_id, msg.child_frame_id, stamp_ns(msg.header.stamp), RigidTransform.from_message(msg.pose.pose, what))

    def frames(self) -> set[str]:
        """Every frame named so far."""
        return set(self._edges) | {e.parent for e in self._edges.values()}

    def newest_stamp(self) -> int | None:
        """The newest dynamic sample's stamp (any edge), or ``None``."""
        newest = [e.times[-1] for e in self._edges.values() if e.times]
        return max(newest) if newest else None

    def lookup(self, target: str, source: str, stamp: int) -> np.ndarray:
        """``T_target_source`` (4x4) at ``stamp``: maps ``source`` coordinates into ``target``."""
        target, source = _clean(target), _clean(source)
        up_source = self._chain(source)
        up_target = self._chain(target)
        common = next((f for f in (source, *[p for p, _ in up_source]) if f == target or f in {p for p, _ in up_target}), None)
        if common is None:
            raise PoseUnavailable(f"no transform chain joins {target!r} and {source!r} (frames known: {', '.join(sorted(self.frames())) or 'none'})")
        root_from_source = self._compose(source, common, stamp)
        root_from_target = self._compose(target, common, stamp)
        return np.linalg.inv(root_from_target) @ root_from_source

    def _chain(self, frame: str) -> list[tuple[str, str]]:
        """``(parent, child)`` pairs from ``frame`` up to its root."""
        out, seen = [], {frame}
        while frame in self._edges:
            parent = self._edges[frame].parent
            if parent in seen:
                break  # a loop in malformed data: stop rather than spin
            out.append((parent, frame))
            seen.add(parent)
            frame = parent
        return out

    def _compose(self, frame: str, ancestor: str, stamp: int) -> np.ndarray:
        m = np.eye(4)
        while frame != ancestor:
            edge = self._edges[frame]
            m = self._at(edge, frame, stamp).matrix() @ m
            frame = edge.parent
        return m

    def _at(self, edge: _Edge, child: str, stamp: int) -> RigidTransform:
        if edge.static is not None:
            return edge.static
        times = edge.times
        if not times:
            raise PoseUnavailable(f"no transform {edge.parent} -> {child} received yet")
        at = bisect.bisect_left(times, stamp)
        nearest = min((i for i in (at - 1, at) if 0 <= i < len(times)), key=lambda i: abs(times[i] - stamp))
        gap = abs(times[nearest] - stamp)
        if gap > self.tolerance_ns:
            raise PoseUnavailable(
                f"transform {edge.parent} -> {child}: the nearest is {gap / 1e9:.3f} s from the image's stamp (tolerance {self.tolerance_ns / 1e9:g} s)"
            )
        if 0 < at < len(times) and times[at - 1] < stamp < times[at]:
            fraction = (stamp - times[at - 1]) / (times[at] - times[at - 1])
            return interpolate(edge.samples[at - 1], edge.samples[at], fraction)
        return edge.samples[nearest]


__all__ = [
    "DEFAULT_CACHE_S",
    "DEFAULT_TOLERANCE_S",
    "MAX_FRAMES",
    "MAX_SAMPLES_PER_EDGE",
    "PoseUnavailable",
    "StampProblem",
    "TransformBuffer",
    "stamp_ns",
]

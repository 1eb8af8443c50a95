"""Rigid transforms as ROS writes them, and the REP 103/105 frame conventions.

A ``geometry_msgs/Transform`` is a translation and a unit quaternion ``(x, y, z, w)``. In a
``TransformStamped`` from ``header.frame_id`` (the parent) to ``child_frame_id`` it is the pose
of the child in the parent: the 4x4 matrix ``T_parent_child`` maps a point in child
coordinates to parent coordinates. Chains compose left to right (``T_map_optical =
T_map_base @ T_base_optical``).

Frame conventions (REP 103 and REP 105): ``map``, ``odom`` and ``base_link`` are body-style,
right-handed, x forward, y left, z up; a camera's ``*_optical_frame`` is z forward, x right,
y down (OpenCV's axes). An image's ``header.frame_id`` names the frame its pixels are in, so
:func:`pose_convention` reads the convention from that name.

Pure: numbers in, numbers out. Nothing here imports rclpy or rosbags.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from povagent.geometry.goals import PoseConvention

#: How far from 1 a quaternion's norm may be before it is refused rather than normalized.
QUATERNION_NORM_TOLERANCE = 1e-3


class TransformProblem(ValueError):
    """A transform that cannot be used (NaN, a zero quaternion); the message says which field."""


@dataclass(frozen=True)
class RigidTransform:
    """A translation (metres) and a unit quaternion ``(x, y, z, w)``: the pose of a child frame in its parent."""

    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]

    @classmethod
    def identity(cls) -> RigidTransform:
        """No motion."""
        return cls((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))

    @classmethod
    def from_message(cls, msg: Any, what: str = "transform") -> RigidTransform:
        """From a ``geometry_msgs/Transform`` (``translation``, ``rotation``) or ``Pose``
        (``position``, ``orientation``); :class:`TransformProblem` naming ``what`` when unusable."""
        t = msg.translation if hasattr(msg, "translation") else msg.position
        q = msg.rotation if hasattr(msg, "rotation") else msg.orientation
        translation = (float(t.x), float(t.y), float(t.z))
        rotation = (float(q.x), float(q.y), float(q.z), float(q.w))
        return cls.checked(translation, rotation, what)

    @classmethod
    def checked(cls, translation: Any, rotation: Any, what: str = "transform") -> RigidTransform:
        """A transform from plain numbers, the quaternion normalized; refused when NaN or not near unit."""
        t = tuple(float(v) for v in translation)
        q = np.asarray(rotation, dtype=float)
        if len(t) != 3 or q.shape != (4,):
            raise TransformProblem(f"{what}: expected a 3-vector and a quaternion (x, y, z, w)")
        if not all(math.isfinite(v) for v in t):
            raise TransformProblem(f"{what}: the translation holds NaN or infinite values")
        if not np.isfinite(q).all():
            raise TransformProblem(f"{what}: the rotation holds NaN or infinite values")
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
            raise TransformProblem(f"{what}: the rotation quaternion has norm {norm:.6g}, not 1")
        q = q / norm
        return cls((t[0], t[1], t[2]), (float(q[0]), float(q[1]), float(q[2]), float(q[3])))

    @classmethod
    def from_matrix(cls, matrix: np.ndarray) -> RigidTransform:
        """From a 4x4 rigid-motion matrix."""
        m = np.asarray(matrix, dtype=float)
        return cls((float(m[0, 3]), float(m[1, 3]), float(m[2, 3])), quaternion_from_rotation(m[:3, :3]))

    def matrix(self) -> np.ndarray:
        """The 4x4 matrix mapping child coordinates to parent coordinates."""
        m = np.eye(4)
        m[:3, :3] = rotation_from_quaternion(self.rotation)
        m[:3, 3] = self.translation
        return m


def rotation_from_quaternion(q: Any) -> np.ndarray:
    """The 3x3 rotation of a unit quaternion ``(x, y, z, w)``."""
    x, y, z, w = (float(v) for v in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_from_rotation(r: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion ``(x, y, z, w)`` of a 3x3 rotation, ``w >= 0`` (Shepperd's method:
    the largest diagonal term picks the branch, so no division by a small number)."""
    m = np.asarray(r, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = (0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s)
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = ((m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = ((m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s)
    v = np.asarray(q, dtype=float)
    v = v / np.linalg.norm(v)
    if v[3] < 0:
        v = -v
    return (float(v[0]), float(v[1]), float(v[2]), float(v[3]))


def slerp(q0: Any, q1: Any, fraction: float) -> tuple[float, float, float, float]:
    """Spherical interpolation between two unit quaternions along the shorter arc."""
    a, b = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    dot = float(a @ b)
    if dot < 0.0:  # q and -q are the same rotation: take the shorter way round
        b, dot = -b, -dot
    if dot > 0.9995:  # nearly equal: linear is exact to rounding and avoids sin(0)
        q = a + fraction * (b - a)
    else:
        theta = math.acos(min(1.0, dot))
        q = (math.sin((1 - fraction) * theta) * a + math.sin(fraction * theta) * b) / math.sin(theta)
    q = q / np.linalg.norm(q)
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def interpolate(before: RigidTransform, after: RigidTransform, fraction: float) -> RigidTransform:
    """The transform ``fraction`` of the way from ``before`` to ``after`` (linear translation,
    spherical rotation), as tf2 interpolates between two stamped transforms."""
    t = tuple(a + fraction * (b - a) for a, b in zip(before.translation, after.translation))
    return RigidTransform((t[0], t[1], t[2]), slerp(before.rotation, after.rotation, fraction))


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (degrees) of the rotation taking the 3x3 rotation ``a`` to ``b``."""
    r = np.asarray(a, dtype=float).T @ np.asarray(b, dtype=float)
    cos = (float(np.trace(r)) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


#: Frame-name endings REP 103 reserves for optical frames (z forward, x right, y down).
OPTICAL_SUFFIXES = ("_optical_frame", "_optical")


def pose_convention(frame_id: str) -> PoseConvention:
    """The axis convention of an image's frame by its name: an ``*_optical_frame`` is OpenCV's
    (z forward, x right, y down); any other frame is a body frame (x forward, y left, z up)."""
    return PoseConvention.OPENCV if frame_id.endswith(OPTICAL_SUFFIXES) else PoseConvention.ROS


__all__ = [
    "OPTICAL_SUFFIXES",
    "RigidTransform",
    "TransformProblem",
    "interpolate",
    "pose_convention",
    "quaternion_from_rotation",
    "rotation_angle",
    "rotation_from_quaternion",
    "slerp",
]

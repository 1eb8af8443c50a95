"""3D navigation goals: back-projecting an answered pixel into the robot's world.

The agent answers with a pixel in one of the robot's frames; a robot needs a point to drive to.
Given that frame's camera this module casts the pixel's ray and returns either

* where it meets a plane (the floor by default), or
* the point at the depth a depth image measures under the pixel.

Two camera descriptions are accepted:

* :class:`povagent.geometry.camera.Camera`, our AI2-THOR camera (left-handed world, y up);
* :class:`PinholeCamera`, a plain 4x4 camera-to-world pose plus intrinsics (a vertical field
  of view, or ``fx, fy, cx, cy``), in one of two axis conventions, ``convention=``:

  - ``"opencv"`` (ROS optical frames, COLMAP): camera x right, y down, z forward;
  - ``"opengl"`` (Blender, ARKit, NeRF): camera x right, y up, looking along -z;
  - ``"ros"`` (a ROS ``camera_link`` / body frame): camera x forward, y left, z up.

  The pose's columns are the world directions of the camera axes and its position; the world
  frame is whatever the pose is expressed in (ROS ``map``/``odom``: z up), and the goal comes
  back in that same frame.

Pixels are continuous coordinates of the camera's own image (``(0, 0)`` the top-left corner,
pixel centres at ``+0.5``; see :mod:`povagent.geometry.letterbox`). Depth images hold metres; ``"z"``
depth (the distance along the optical axis, what depth cameras and renderers give) or
``"range"`` depth (the distance along the ray). A depth image may have another resolution than
the colour frame: it is sampled at the same image fraction.

Pure: numbers in, numbers out; no files, no clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Literal, Sequence

import numpy as np

from povagent.geometry.camera import BEHIND_EPSILON, Camera
from povagent.geometry.letterbox import Letterbox


class PoseConvention(StrEnum):
    """Axis convention of a camera-to-world pose's camera frame."""

    #: x right, y down, z forward (the optical axis)
    OPENCV = "opencv"
    #: x right, y up, z backward (the camera looks along -z)
    OPENGL = "opengl"
    #: x forward, y left, z up (ROS body frames such as ``camera_link``; REP 103)
    ROS = "ros"


#: Columns: the OpenCV axes (right, down, forward) in each convention's camera frame. Every
#: convention is right-handed, so the pose's handedness is the world's.
_TO_OPENCV = {
    PoseConvention.OPENCV: np.diag([1.0, 1.0, 1.0]),
    PoseConvention.OPENGL: np.diag([1.0, -1.0, -1.0]),
    PoseConvention.ROS: np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]),
}


@dataclass(frozen=True)
class PinholeCamera:
    """A pinhole camera from a 4x4 camera-to-world pose and intrinsics in pixels.

    ``fx, fy`` are focal lengths and ``cx, cy`` the principal point, in pixels of a
    ``width`` x ``height`` image, on the continuous convention (the centre of a
    ``W`` x ``H`` image is ``(W/2, H/2)``; OpenCV calibrations put it at
    ``((W-1)/2, (H-1)/2)`` on pixel-index coordinates: add 0.5 to convert). ``content``, when
    set, is the part of the image showing the scene (a letterboxed frame's content,
    :meth:`letterboxed`); by default all of it.
    """

    camera_to_world: np.ndarray = field(repr=False)
    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    convention: PoseConvention = PoseConvention.OPENCV
    content: tuple[float, float, float, float] | None = None

    def __post_init__(self) -> None:
        pose = np.asarray(self.camera_to_world, dtype=float)
        if pose.shape != (4, 4):
            raise ValueError(f"camera_to_world must be a 4x4 matrix, got shape {pose.shape}")
        if not np.all(np.isfinite(pose)):
            raise ValueError("camera_to_world holds NaN or infinite values")
        rot = pose[:3, :3]
        # orthonormal columns (a rotation, or a reflection for left-handed worlds such as Unity's)
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-4):
            raise ValueError("camera_to_world's 3x3 part is not orthonormal (is it world-to-camera, or scaled?)")
        if not np.all(np.isfinite([self.fx, self.fy, self.cx, self.cy])):
            raise ValueError("intrinsics hold NaN or infinite values")
        if self.fx <= 0 or self.fy <= 0 or self.width < 1 or self.height < 1:
            raise ValueError("focal lengths and image size must be positive")
        object.__setattr__(self, "camera_to_world", pose)
        object.__setattr__(self, "convention", PoseConvention(self.convention))

    @classmethod
    def from_fov(
        cls,
        camera_to_world: Sequence[Sequence[float]] | np.ndarray,
        vertical_fov: float,
        width: int,
        height: int,
        convention: PoseConvention | str = PoseConvention.OPENCV,
    ) -> PinholeCamera:
        """Square pixels, principal point at the image centre, ``vertical_fov`` in degrees."""
        if not 0 < vertical_fov < 180:
            raise ValueError(f"vertical_fov must be in (0, 180) degrees, got {vertical_fov}")
        f = (height / 2.0) / np.tan(np.radians(vertical_fov) / 2.0)
        return cls(np.asarray(camera_to_world, dtype=float), f, f, width / 2.0, height / 2.0, int(width), int(height),
                   PoseConvention(convention))

    @classmethod
    def from_intrinsics(
        cls,
        camera_to_world: Sequence[Sequence[float]] | np.ndarray,
        intrinsics: Sequence[Sequence[float]] | np.ndarray,
        width: int,
        height: int,
        convention: PoseConvention | str = PoseConvention.OPENCV,
    ) -> PinholeCamera:
        """From a 3x3 intrinsic matrix ``K`` (``fx, fy`` on the diagonal, ``cx, cy`` in the last column)."""
        k = np.asarray(intrinsics, dtype=float)
        if k.shape != (3, 3):
            raise ValueError(f"intrinsics must be a 3x3 matrix, got shape {k.shape}")
        return cls(np.asarray(camera_to_world, dtype=float), float(k[0, 0]), float(k[1, 1]), float(k[0, 2]),
                   float(k[1, 2]), int(width), int(height), PoseConvention(convention))

    @classmethod
    def from_camera(cls, camera: Camera, convention: PoseConvention | str = PoseConvention.OPENCV) -> PinholeCamera:
        """Our AI2-THOR camera as a 4x4 pose (a reflection: Unity's world is left-handed)."""
        convention = PoseConvention(convention)
        right, up, forward = camera.axes()
        opencv_axes = np.stack([right, -up, forward], axis=1)  # columns: x right, y down, z forward
        pose = np.eye(4)
        pose[:3, :3] = opencv_axes @ _TO_OPENCV[convention].T  # the inverse of a rotation
        pose[:3, 3] = camera.position
        # our camera's fov spans the width (as the official scorer has it): take its focal length
        f = float(camera.focal_px)
        return cls(pose, f, f, camera.width / 2.0, camera.height / 2.0, int(camera.width), int(camera.height), convention)

    @property
    def position(self) -> np.ndarray:
        """Camera centre in world coordinates."""
        return self.camera_to_world[:3, 3]

    @property
    def fov(self) -> float:
        """Horizontal field of view (degrees) across the width, as :class:`Camera`'s."""
        return float(np.degrees(2.0 * np.arctan2(self.width / 2.0, self.fx)))

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """``(fx, fy, cx, cy)`` in pixels."""
        return (float(self.fx), float(self.fy), float(self.cx), float(self.cy))

    @property
    def content_box(self) -> tuple[float, float, float, float]:
        """``(left, top, right, bottom)`` of the image content (the whole image unless letterboxed)."""
        return self.content if self.content is not None else (0.0, 0.0, float(self.width), float(self.height))

    @property
    def right_handed(self) -> bool:
        """Whether the pose's world is right-handed (ROS, OpenCV, OpenGL) rather than left-handed (Unity)."""
        return bool(np.linalg.det(self._opencv_to_world()) > 0)

    def optical_axes(self) -> np.ndarray:
        """Rows ``right, down, forward`` (in world coordinates) as a (3, 3) world-to-camera map."""
        return self._opencv_to_world().T

    def letterboxed(self, box: Letterbox) -> PinholeCamera:
        """The same camera describing the letterboxed square ``box`` makes of its frame.

        The letterbox scales and shifts pixels per axis, so the intrinsics follow exactly:
        ``fx' = fx sx``, ``cx' = ox + cx sx`` (likewise for y); ``content`` is the frame's place
        in the square.
        """
        if box.original != (self.width, self.height):
            raise ValueError(f"the letterbox was made for {box.original[0]}x{box.original[1]}, the camera is {self.width}x{self.height}")
        sx, sy = box.scale
        ox, oy = box.offset
        left, top, right, bottom = box.content_box()
        return PinholeCamera(self.camera_to_world, self.fx * sx, self.fy * sy, ox + self.cx * sx, oy + self.cy * sy, box.size, box.size,
                             self.convention, (float(left), float(top), float(right), float(bottom)))

    def moved(self, rotation: np.ndarray, origin: Sequence[float] | np.ndarray) -> PinholeCamera:
        """The same camera in another world frame, ``p' = rotation (p - origin)`` (``rotation``
        orthonormal; a reflection changes the world's handedness)."""
        r = np.asarray(rotation, dtype=float)
        pose = np.eye(4)
        pose[:3, :3] = r @ self.camera_to_world[:3, :3]
        pose[:3, 3] = r @ (self.position - np.asarray(origin, dtype=float))
        return PinholeCamera(pose, self.fx, self.fy, self.cx, self.cy, self.width, self.height, self.convention, self.content)

    def _opencv_to_world(self) -> np.ndarray:
        # world directions of the OpenCV axes (right, down, forward) as columns
        return self.camera_to_world[:3, :3] @ _TO_OPENCV[self.convention]

    def ray(self, pixels: np.ndarray) -> np.ndarray:
        """Unit world directions ``(..., 3)`` through pixel coordinates ``(..., 2)``."""
        cam = self._opencv_directions(pixels)
        world = cam @ self._opencv_to_world().T
        return world / np.linalg.norm(world, axis=-1, keepdims=True)

    def point_at_depth(self, pixels: np.ndarray, depth: np.ndarray | float) -> np.ndarray:
        """World point at optical-axis ``depth`` (metres along the viewing direction) under each pixel."""
        cam = self._opencv_directions(pixels) * np.asarray(depth, dtype=float)[..., None]
        return cam @ self._opencv_to_world().T + self.position

    def project_pixels(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 3)`` to pixel coordinates ``(..., 2)`` (NaN behind the camera)."""
        d = np.asarray(points, dtype=float) - self.position
        cam = d @ self._opencv_to_world()
        z = np.where(cam[..., 2] > BEHIND_EPSILON, cam[..., 2], np.nan)
        return np.stack([self.fx * cam[..., 0] / z + self.cx, self.fy * cam[..., 1] / z + self.cy], axis=-1)

    def project_point(self, point: Sequence[float] | np.ndarray) -> tuple[float, float, float]:
        """One world point: ``(u/W, v/H, depth)`` (depth along the optical axis); the fractions
        are NaN when the point is behind the camera (``depth <= 1e-6``), as :class:`Camera`'s."""
        cam = (np.asarray(point, dtype=float) - self.position) @ self._opencv_to_world()
        z = float(cam[2])
        if not z > BEHIND_EPSILON:
            return (math.nan, math.nan, z)
        return ((self.fx * cam[0] / z + self.cx) / self.width, (self.fy * cam[1] / z + self.cy) / self.height, z)

    def _opencv_directions(self, pixels: np.ndarray) -> np.ndarray:
        p = np.asarray(pixels, dtype=float)
        x = (p[..., 0] - self.cx) / self.fx
        y = (p[..., 1] - self.cy) / self.fy
        return np.stack([x, y, np.ones_like(x)], axis=-1)


#: What a goal can be computed from.
GoalCamera = Camera | PinholeCamera


@dataclass(frozen=True)
class Plane:
    """A plane ``{p : (p - point) . normal = 0}`` in world coordinates.

    The default is AI2-THOR's floor (``y = 0``, y up); a ROS robot's floor is
    ``Plane(normal=(0, 0, 1))``.
    """

    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 1.0, 0.0)

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=float)
        if n.shape != (3,) or not np.isfinite(n).all() or np.linalg.norm(n) < 1e-12:
            raise ValueError(f"plane normal must be a non-zero 3-vector, got {self.normal!r}")

    @classmethod
    def horizontal(cls, height: float = 0.0, up_axis: Literal["y", "z"] = "y") -> Plane:
        """The horizontal plane at ``height`` in a y-up (AI2-THOR) or z-up (ROS) world."""
        if up_axis == "y":
            return cls((0.0, float(height), 0.0), (0.0, 1.0, 0.0))
        return cls((0.0, 0.0, float(height)), (0.0, 0.0, 1.0))


#: AI2-THOR's floor.
FLOOR = Plane()


@dataclass(frozen=True)
class Goal3D:
    """A 3D goal in the camera's world frame.

    ``method`` says how it was found (``"depth"``, ``"plane"``, or ``"geometry"``: worked out by
    a strategy that solves the geometry itself, such as ``geometric``); ``distance`` is how far it is
    from the camera centre along the ray (metres); ``pixel`` is the pixel it came from.
    """

    point: tuple[float, float, float]
    method: Literal["depth", "plane", "geometry"]
    distance: float
    pixel: tuple[float, float]


class GoalUnavailable(ValueError):
    """No 3D point under a pixel: the ray misses the plane, or the depth there is invalid."""


def camera_size(camera: GoalCamera) -> tuple[int, int]:
    """``(width, height)`` of the image the camera describes."""
    return (camera.width, camera.height)


def camera_position(camera: GoalCamera) -> np.ndarray:
    """The camera centre in world coordinates."""
    return np.asarray(camera.position, dtype=float)


def on_plane(camera: GoalCamera, pixel: Sequence[float], plane: Plane = FLOOR) -> Goal3D:
    """Where ``pixel``'s ray meets ``plane``.

    Raises :class:`GoalUnavailable` when the ray is parallel to the plane or meets it behind
    the camera (a pixel above the horizon, for the floor).
    """
    origin = camera_position(camera)
    direction = camera.ray(np.asarray(pixel, dtype=float))
    normal = np.asarray(plane.normal, dtype=float)
    denom = float(direction @ normal)
    if abs(denom) < 1e-9:
        raise GoalUnavailable(f"the ray through pixel ({pixel[0]:.1f}, {pixel[1]:.1f}) is parallel to the plane")
    t = float((np.asarray(plane.point, dtype=float) - origin) @ normal) / denom
    if t <= 0:
        raise GoalUnavailable(
            f"the ray through pixel ({pixel[0]:.1f}, {pixel[1]:.1f}) meets the plane behind the camera "
            "(above the horizon, for the floor)"
        )
    point = origin + t * direction
    return Goal3D(_tuple3(point), "plane", t, (float(pixel[0]), float(pixel[1])))


def depth_at(depth: np.ndarray, pixel: Sequence[float], size: tuple[int, int]) -> float:
    """The depth image's value under a pixel of a ``size`` = ``(W, H)`` colour frame.

    The depth image is sampled at the same image fraction (nearest pixel), so a 640x480 depth
    map serves a 1280x960 colour frame.
    """
    d = np.asarray(depth)
    if d.ndim == 3 and d.shape[2] == 1:
        d = d[..., 0]
    if d.ndim != 2:
        raise ValueError(f"a depth image must be 2D (H, W), got shape {d.shape}")
    rows, cols = d.shape
    col = int(np.clip(np.floor(pixel[0] / size[0] * cols), 0, cols - 1))
    row = int(np.clip(np.floor(pixel[1] / size[1] * rows), 0, rows - 1))
    return float(d[row, col])


def at_depth(
    camera: GoalCamera,
    pixel: Sequence[float],
    depth: np.ndarray,
    *,
    depth_kind: Literal["z", "range"] = "z",
) -> Goal3D:
    """The point the depth image measures under ``pixel``.

    ``depth_kind`` ``"z"``: optical-axis depth; ``"range"``: distance along the ray. Raises
    :class:`GoalUnavailable` for a missing reading (0, negative, NaN or infinite).
    """
    value = depth_at(depth, pixel, camera_size(camera))
    if not np.isfinite(value) or value <= 0:
        raise GoalUnavailable(f"no valid depth under pixel ({pixel[0]:.1f}, {pixel[1]:.1f}) (read {value})")
    p = np.asarray(pixel, dtype=float)
    origin = camera_position(camera)
    if depth_kind == "z":
        point = camera.point_at_depth(p, value)
    elif depth_kind == "range":
        point = origin + camera.ray(p) * value
    else:
        raise ValueError(f"depth_kind must be 'z' or 'range', got {depth_kind!r}")
    return Goal3D(_tuple3(point), "depth", float(np.linalg.norm(point - origin)), (float(p[0]), float(p[1])))


def back_project(
    camera: GoalCamera,
    pixel: Sequence[float],
    *,
    depth: np.ndarray | None = None,
    plane: Plane = FLOOR,
    depth_kind: Literal["z", "range"] = "z",
) -> Goal3D:
    """The 3D goal under ``pixel``: at the measured depth when ``depth`` is given, else on ``plane``.

    A missing depth reading is not replaced by the plane silently: it raises
    :class:`GoalUnavailable`, so the caller decides.
    """
    if depth is not None:
        return at_depth(camera, pixel, depth, depth_kind=depth_kind)
    return on_plane(camera, pixel, plane)


def _tuple3(p: np.ndarray) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]))


def camera_problem(camera: GoalCamera) -> str | None:
    """What makes ``camera`` unusable (NaN or infinite numbers, a pose that is not a rigid
    motion, a non-positive size or focal length), or ``None`` when it is fine.

    :class:`PinholeCamera` checks itself when built; its pose is a numpy array, which the
    caller may still change in place afterwards, so a consumer checks again before use.
    """
    if isinstance(camera, PinholeCamera):
        pose = np.asarray(camera.camera_to_world, dtype=float)
        if pose.shape != (4, 4):
            return f"the camera-to-world pose must be 4x4, got shape {pose.shape}"
        if not np.all(np.isfinite(pose)):
            return "the camera-to-world pose holds NaN or infinite values"
        rot = pose[:3, :3]
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-4) or not np.allclose(pose[3], (0.0, 0.0, 0.0, 1.0)):
            return "the camera-to-world pose is not a rigid motion (its 3x3 part is not orthonormal: scaled, sheared, or world-to-camera?)"
        numbers: tuple[float, ...] = (camera.fx, camera.fy, camera.cx, camera.cy)
    else:
        numbers = (*camera.position, camera.yaw, camera.horizon, camera.fov)
        if np.all(np.isfinite(numbers)) and not 0 < camera.fov < 180:
            return f"fov must be in (0, 180) degrees, got {camera.fov}"
    if not np.all(np.isfinite(np.asarray(numbers, dtype=float))):
        return "the camera holds NaN or infinite values"
    if isinstance(camera, PinholeCamera) and (camera.fx <= 0 or camera.fy <= 0):
        return f"focal lengths must be positive, got fx={camera.fx}, fy={camera.fy}"
    if camera.width < 1 or camera.height < 1:
        return f"the image size must be positive, got {camera.width}x{camera.height}"
    return None

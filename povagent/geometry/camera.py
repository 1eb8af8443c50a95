"""The AI2-THOR (Unity) pinhole camera: left-handed world, y up, degrees.

Yaw turns about +y, positive horizon tilts the view down, and ``fov`` sets the focal length from
the frame's *width*, as the official scorer computes it (``f = (W/2)/tan(fov/2)``, used for both
axes: square pixels). For the square 512x512 frames of POVBench it is both the horizontal and the
vertical field of view; for a non-square frame it is the horizontal one. Everything here is pure
and vectorized: points are arrays of shape ``(..., 3)``.

Camera axes for yaw ``y`` and horizon ``h``::

    right   = ( cos y,        0,      -sin y)
    forward = ( sin y cos h, -sin h,   cos y cos h)
    up      = ( sin y sin h,  cos h,   cos y sin h)

A world point ``p`` has camera coordinates ``(d.right, d.up, d.forward)`` with ``d = p - pos``
and projects to ``u = f xc/zc + W/2``, ``v = H/2 - f yc/zc`` pixels, ``f = (W/2)/tan(fov/2)``.

:class:`ViewCamera` is what the geometric solver asks of a frame's camera; :class:`Camera` and
the robot's :class:`~povagent.geometry.goals.PinholeCamera` both are one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np

#: Depth at or below which a point counts as behind the camera (as the official scorer does).
BEHIND_EPSILON = 1e-6


@dataclass(frozen=True)
class Projection:
    """Where world points land in a camera.

    ``normalized`` is ``(..., 2)`` in image fractions (u/W, v/H), unclamped; ``depth`` is the
    distance along the optical axis; ``in_front`` is ``depth > 1e-6``; ``in_frame`` adds
    ``0 <= u/W <= 1`` and ``0 <= v/H <= 1``.
    """

    normalized: np.ndarray
    depth: np.ndarray
    in_front: np.ndarray
    in_frame: np.ndarray


class ViewCamera(Protocol):
    """What the geometric solver needs of a frame's camera (:class:`Camera`, or a robot's
    :class:`~povagent.geometry.goals.PinholeCamera` brought into the benchmark's world).

    Pixels are continuous coordinates of a ``width`` x ``height`` image; ``content_box`` is the
    part of it showing the scene (all of it, or a letterbox's content: its border is the edge
    of the view, not of an object).
    """

    @property
    def position(self) -> Sequence[float] | np.ndarray:
        """Camera centre in world coordinates."""
        ...

    @property
    def width(self) -> int:
        """Image width (px)."""
        ...

    @property
    def height(self) -> int:
        """Image height (px)."""
        ...

    @property
    def fov(self) -> float:
        """Horizontal field of view (degrees) across the width."""
        ...

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """``(fx, fy, cx, cy)`` in pixels: ``u = fx x/z + cx``, ``v = fy y/z + cy`` on the
        optical axes of :meth:`optical_axes`."""
        ...

    @property
    def content_box(self) -> tuple[float, float, float, float]:
        """``(left, top, right, bottom)`` of the image content (pixels)."""
        ...

    def optical_axes(self) -> np.ndarray:
        """Rows ``right, down, forward`` (OpenCV's optical axes) as a (3, 3) world-to-camera rotation."""
        ...

    def ray(self, pixels: np.ndarray) -> np.ndarray:
        """Unit world directions ``(..., 3)`` through pixel coordinates ``(..., 2)``."""
        ...

    def project_point(self, point: Sequence[float] | np.ndarray) -> tuple[float, float, float]:
        """One world point: ``(u/W, v/H, depth)``; NaN fractions behind the camera."""
        ...

    def project_pixels(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 3)`` to pixel coordinates ``(..., 2)`` (NaN behind the camera)."""
        ...


@dataclass(frozen=True)
class Camera:
    """A pinhole camera posed like AI2-THOR's: position, yaw, horizon, fov (across the width), size."""

    position: tuple[float, float, float]
    yaw: float
    horizon: float
    fov: float = 100.0
    width: int = 512
    height: int = 512

    @classmethod
    def from_pose(
        cls,
        position: Sequence[float],
        yaw: float,
        horizon: float,
        fov: float = 100.0,
        width: int = 512,
        height: int = 512,
    ) -> Camera:
        """Build a camera from any 3-sequence position (list, tuple, array)."""
        x, y, z = (float(v) for v in position)
        return cls((x, y, z), float(yaw), float(horizon), float(fov), int(width), int(height))

    # -- frame --------------------------------------------------------------------------------
    @property
    def focal_px(self) -> float:
        """Focal length in pixels: ``(W/2)/tan(fov/2)``, the width's field of view (as officially)."""
        return (self.width / 2.0) / math.tan(math.radians(self.fov) / 2.0)  # libm: numpy's tan differs by CPU

    def axes(self) -> np.ndarray:
        """Rows ``right, up, forward`` as a (3, 3) world-to-camera rotation."""
        y, h = np.radians(self.yaw), np.radians(self.horizon)
        sy, cy, sh, ch = np.sin(y), np.cos(y), np.sin(h), np.cos(h)
        return np.array(
            [
                [cy, 0.0, -sy],
                [sy * sh, ch, cy * sh],
                [sy * ch, -sh, cy * ch],
            ]
        )

    def optical_axes(self) -> np.ndarray:
        """Rows ``right, down, forward``: :meth:`axes` with ``up`` turned to ``down``."""
        axes = self.axes()
        axes[1] = -axes[1]
        return axes

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """``(f, f, W/2, H/2)``: square pixels, the principal point at the image centre."""
        f = float(self.focal_px)
        return (f, f, self.width / 2.0, self.height / 2.0)

    @property
    def content_box(self) -> tuple[float, float, float, float]:
        """The whole image: ``(0, 0, W, H)``."""
        return (0.0, 0.0, float(self.width), float(self.height))

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 3)`` to camera coordinates ``(xc, yc, zc)`` (right, up, forward)."""
        d = np.asarray(points, dtype=float) - np.asarray(self.position)
        return d @ self.axes().T

    # -- the floor seen from the camera ---------------------------------------------------------
    def floor_offset(self, point: Sequence[float] | np.ndarray) -> tuple[float, float]:
        """Where ``point`` is on the floor plane relative to the camera, in metres: along the
        camera's right and along its heading (its forward with the horizon's tilt taken out).
        Heights are ignored: a point 1 m straight below the camera is ``(0, 0)``."""
        y = math.radians(self.yaw)
        dx, dz = float(point[0]) - self.position[0], float(point[2]) - self.position[2]
        return (dx * math.cos(y) - dz * math.sin(y), dx * math.sin(y) + dz * math.cos(y))

    def floor_point(self, right: float, ahead: float, height: float = 0.0) -> np.ndarray:
        """The world point ``right`` metres to the camera's right and ``ahead`` along its heading,
        at ``height``: the inverse of :meth:`floor_offset`."""
        y = math.radians(self.yaw)
        x = self.position[0] + right * math.cos(y) + ahead * math.sin(y)
        z = self.position[2] - right * math.sin(y) + ahead * math.cos(y)
        return np.array([x, height, z])

    # -- projection ---------------------------------------------------------------------------
    def project(self, points: np.ndarray) -> Projection:
        """Project world points; points behind the camera get NaN coordinates."""
        c = self.to_camera(points)
        depth = c[..., 2]
        in_front = depth > BEHIND_EPSILON
        f = self.focal_px
        with np.errstate(divide="ignore", invalid="ignore"):
            safe = np.where(in_front, depth, np.nan)
            u = (f * c[..., 0] / safe + self.width / 2.0) / self.width
            v = (self.height / 2.0 - f * c[..., 1] / safe) / self.height
        normalized = np.stack([u, v], axis=-1)
        with np.errstate(invalid="ignore"):
            in_frame = in_front & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
        return Projection(normalized, depth, in_front, in_frame)

    def project_point(self, point: Sequence[float] | np.ndarray) -> tuple[float, float, float]:
        """One world point: ``(u/W, v/H, depth)``, unclamped; ``u/W`` and ``v/H`` are NaN when
        the point is behind the camera (``depth <= 1e-6``).

        The arithmetic of :meth:`project` for a single point in plain floats: scoring projects
        one GT point per row, thousands of times a run, where numpy's per-call cost dominates.
        """
        y, h = math.radians(self.yaw), math.radians(self.horizon)
        sy, cy, sh, ch = math.sin(y), math.cos(y), math.sin(h), math.cos(h)
        px, py, pz = self.position
        dx, dy, dz = float(point[0]) - px, float(point[1]) - py, float(point[2]) - pz
        xc = cy * dx - sy * dz
        yc = sy * sh * dx + ch * dy + cy * sh * dz
        zc = sy * ch * dx - sh * dy + cy * ch * dz
        if not zc > BEHIND_EPSILON:
            return (math.nan, math.nan, zc)
        f = (self.width / 2.0) / math.tan(math.radians(self.fov) / 2.0)
        return ((f * xc / zc + self.width / 2.0) / self.width, (self.height / 2.0 - f * yc / zc) / self.height, zc)

    def project_pixels(self, points: np.ndarray) -> np.ndarray:
        """Project world points to pixel coordinates ``(..., 2)`` (NaN behind the camera)."""
        n = self.project(points).normalized
        return n * np.array([self.width, self.height], dtype=float)

    # -- back-projection ----------------------------------------------------------------------
    def ray(self, pixels: np.ndarray) -> np.ndarray:
        """Unit world-space ray directions ``(..., 3)`` through pixel coordinates ``(..., 2)``.

        A pixel with a NaN or infinite coordinate (a model's answer past float range) has no
        ray: its row is NaN, as a point behind the camera projects to NaN. Without that rule the
        matrix product mixes ``inf * 0`` into the row, which is NaN too but warns on every call.
        """
        p = np.asarray(pixels, dtype=float)
        f = self.focal_px
        finite = np.isfinite(p).all(axis=-1)
        p = np.where(finite[..., None], p, 0.0)  # a stand-in, replaced by NaN below
        xc = (p[..., 0] - self.width / 2.0) / f
        yc = (self.height / 2.0 - p[..., 1]) / f
        cam = np.stack([xc, yc, np.ones_like(xc)], axis=-1)
        world = cam @ self.axes()
        rays = world / np.linalg.norm(world, axis=-1, keepdims=True)
        return np.where(finite[..., None], rays, np.nan)

    def point_at_depth(self, pixels: np.ndarray, depth: np.ndarray | float) -> np.ndarray:
        """World point at optical-axis ``depth`` (metres along forward) under each pixel."""
        p = np.asarray(pixels, dtype=float)
        f = self.focal_px
        z = np.asarray(depth, dtype=float)
        xc = (p[..., 0] - self.width / 2.0) / f * z
        yc = (self.height / 2.0 - p[..., 1]) / f * z
        cam = np.stack([xc, yc, np.broadcast_to(z, xc.shape)], axis=-1)
        return cam @ self.axes() + np.asarray(self.position)

    def point_on_plane(self, pixels: np.ndarray, plane_y: float = 0.0) -> np.ndarray:
        """Where each pixel's ray meets the horizontal plane ``y = plane_y``.

        Rays parallel to the plane or meeting it behind the camera give NaN.
        """
        dirs = self.ray(pixels)
        origin = np.asarray(self.position)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (plane_y - origin[1]) / dirs[..., 1]
        t = np.where(np.isfinite(t) & (t > 0), t, np.nan)
        return origin + dirs * t[..., None]

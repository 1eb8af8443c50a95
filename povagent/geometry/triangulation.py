"""Where a perceived object is in 3D: rays through pointed pixels, met across views or against
a height prior, and an axis-aligned box fitted to its outlines.

A model points at an object in frames whose cameras are known (a robot knows its poses; the
release records every exploration camera). Two or more views with enough angle between their
rays fix the point (least squares over the rays); one view, or views whose rays are nearly
parallel, fix it by where the ray meets the height the object's centre usually has (see
:mod:`povagent.geometry.size_priors`). Outlines (2D boxes) then give the object's extent.
Pure numpy and scipy over any :class:`~povagent.geometry.camera.ViewCamera` (the release's
AI2-THOR cameras, or a robot's pinhole cameras brought into the benchmark's world, y up with the
floor at ``y = 0``): no files, no model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from povagent.geometry.camera import ViewCamera

#: Smallest angle (degrees) between two views' rays for a triangulation to be trusted: below
#: it the rays are nearly parallel and the depth along them is mostly pointing noise.
MIN_RAY_ANGLE_DEG = 4.0
#: Nearest a triangulated point may be to a camera that saw it (m, along the optical axis).
MIN_DEPTH = 0.1
#: Where a ray that never meets the prior height is cut (m): pointing above the horizon at an
#: object whose usual centre is below the camera, say. A guess, and the solver says so.
FALLBACK_RANGE = 2.5
#: A box edge this close to the image border (px) was cut by the border: it bounds nothing.
CLIPPED_EDGE_PX = 1.5
#: Pointing noise (px) the box fit assumes; it only sets how much the priors weigh.
BOX_EDGE_SIGMA_PX = 4.0
#: How far (log scale) an object's height and footprint may stray from their priors.
SIZE_PRIOR_SIGMA = 1.0


@dataclass(frozen=True)
class Sighting:
    """One view of an object: the frame's camera and the pixel pointed at (its centre)."""

    camera: ViewCamera
    pixel: tuple[float, float]


@dataclass(frozen=True)
class Outline:
    """One view of an object's extent: the camera and the 2D box ``(x0, y0, x1, y1)`` in pixels."""

    camera: ViewCamera
    box: tuple[float, float, float, float]


@dataclass(frozen=True)
class PointEstimate:
    """A located point: how it was found (``"triangulated"`` or ``"height prior"``), from how
    many views, and the largest angle between their rays (degrees)."""

    point: tuple[float, float, float]
    method: str
    views: int
    spread_deg: float


def _rays(sightings: Sequence[Sighting]) -> tuple[np.ndarray, np.ndarray]:
    origins = np.array([s.camera.position for s in sightings], dtype=float)
    dirs = np.array([s.camera.ray(np.asarray(s.pixel, dtype=float)) for s in sightings], dtype=float)
    return origins, dirs


def ray_spread_deg(directions: np.ndarray) -> float:
    """The largest angle (degrees) between any two unit directions (0 for fewer than two)."""
    if len(directions) < 2:
        return 0.0
    cos = np.clip(directions @ directions.T, -1.0, 1.0)
    return float(np.degrees(np.arccos(cos.min())))


def closest_point_to_rays(origins: np.ndarray, directions: np.ndarray) -> np.ndarray | None:
    """The point nearest (least squares) to every ray; ``None`` when the rays are parallel."""
    eye = np.eye(3)
    a = np.zeros((3, 3))
    b = np.zeros(3)
    for o, d in zip(origins, directions):
        m = eye - np.outer(d, d)
        a += m
        b += m @ o
    if np.linalg.cond(a) > 1e8:
        return None
    return np.linalg.solve(a, b)


def meet_height(sighting: Sighting, height: float) -> tuple[np.ndarray, bool]:
    """Where the pointed ray meets the plane ``y = height``: ``(point, met)``. A ray that never
    meets it (parallel, or meeting it behind the camera) is cut at :data:`FALLBACK_RANGE`."""
    cam = sighting.camera
    pixel = np.asarray(sighting.pixel, dtype=float)
    direction = cam.ray(pixel)
    origin = np.asarray(cam.position, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (height - origin[1]) / direction[..., 1]
    t = np.where(np.isfinite(t) & (t > 0), t, np.nan)
    p = origin + direction * t[..., None]
    if np.all(np.isfinite(p)):
        return p, True
    return origin + FALLBACK_RANGE * direction, False


def locate(sightings: Sequence[Sighting], centre_height: float, min_angle_deg: float = MIN_RAY_ANGLE_DEG) -> PointEstimate | None:
    """Locate one object from its sightings (``None`` without any).

    Triangulated when two or more rays span at least ``min_angle_deg`` and the point lies in
    front of every camera; otherwise each ray meets ``centre_height`` (the type's prior) and
    the points are averaged.
    """
    if not sightings:
        return None
    origins, dirs = _rays(sightings)
    spread = ray_spread_deg(dirs)
    if len(sightings) >= 2 and spread >= min_angle_deg:
        p = closest_point_to_rays(origins, dirs)
        if p is not None and all(s.camera.project_point(p)[2] > MIN_DEPTH for s in sightings):
            return PointEstimate((float(p[0]), float(p[1]), float(p[2])), "triangulated", len(sightings), spread)
    points = [meet_height(s, centre_height)[0] for s in sightings]
    mean = np.mean(points, axis=0)
    return PointEstimate((float(mean[0]), float(mean[1]), float(mean[2])), "height prior", len(sightings), spread)


def box_corners(centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """The 8 corners ``(8, 3)`` of an axis-aligned box."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    return np.asarray(centre, dtype=float) + signs * np.asarray(half, dtype=float)


def optical_depth(camera: ViewCamera, points: np.ndarray) -> np.ndarray:
    """Depth ``(...)`` of world points ``(..., 3)`` along the camera's optical axis (m)."""
    return ((np.asarray(points, dtype=float) - np.asarray(camera.position, dtype=float)) @ camera.optical_axes().T)[..., 2]


def projected_box(camera: ViewCamera, centre: np.ndarray, half: np.ndarray) -> tuple[float, float, float, float] | None:
    """The 2D box (pixels, unclipped) around a 3D box's corners; ``None`` if a corner is behind."""
    corners = box_corners(centre, half)
    depth = optical_depth(camera, corners)
    if np.any(depth <= MIN_DEPTH):
        return None
    px = camera.project_pixels(corners)
    return (float(px[:, 0].min()), float(px[:, 1].min()), float(px[:, 0].max()), float(px[:, 1].max()))


@dataclass(frozen=True)
class BoxEstimate:
    """An object's axis-aligned box: centre, half sizes ``(hx, hy, hz)``, and how many box
    edges measured it (0: the size is the prior's alone)."""

    centre: tuple[float, float, float]
    half: tuple[float, float, float]
    edges_used: int

    @property
    def top(self) -> float:
        """The highest y of the box."""
        return self.centre[1] + self.half[1]


def fit_box(
    centre: Sequence[float],
    outlines: Sequence[Outline],
    prior_half: tuple[float, float, float],
    centre_sigma: float = 0.15,
) -> BoxEstimate:
    """Fit an axis-aligned box to 2D outlines seen from known cameras.

    Unknowns: the centre (starting at ``centre``, held to it within ``centre_sigma`` metres)
    and the half sizes (held to ``prior_half``'s height and footprint area within
    :data:`SIZE_PRIOR_SIGMA` in log scale, orientation free). Box edges cut by the image
    border (of the image content: a letterbox's padding is no object's edge) bound nothing and
    are left out. Without a usable edge the prior size is returned.
    """
    from scipy.optimize import least_squares

    c0 = np.asarray(centre, dtype=float)
    prior = np.maximum(np.asarray(prior_half, dtype=float), 0.02)
    views: list[int] = []
    sides: list[int] = []
    values: list[float] = []
    for i, o in enumerate(outlines):
        left, top, right, bottom = o.camera.content_box
        first, last = (left, top), (right - 1.0, bottom - 1.0)
        for k in range(4):
            v = float(o.box[k])
            lower, upper = first[k % 2], last[k % 2]
            if lower + CLIPPED_EDGE_PX < v < upper - CLIPPED_EDGE_PX:
                views.append(i)
                sides.append(k)
                values.append(v)
    if not values:
        return BoxEstimate(tuple(float(v) for v in c0), tuple(float(v) for v in prior), 0)  # type: ignore[arg-type]
    cams = [o.camera for o in outlines]
    rotations = np.stack([c.optical_axes() for c in cams])  # (V, 3, 3): rows right, down, forward
    positions = np.array([c.position for c in cams], dtype=float)
    fx, fy, cx, cy = (np.array(v, dtype=float)[:, None] for v in zip(*(c.intrinsics for c in cams)))
    view_idx, side_idx, measured = np.array(views), np.array(sides), np.array(values)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    log_prior_h = math.log(prior[1])
    log_prior_area = math.log(prior[0] * prior[2])

    def residuals(x: np.ndarray) -> np.ndarray:
        corners = x[:3] + signs * np.exp(x[3:])  # (8, 3)
        local = np.einsum("vij,vkj->vki", rotations, corners[None, :, :] - positions[:, None, :])  # (V, 8, 3)
        # a corner reaching behind the camera projects as if just in front of it: far outside
        # the image, so the fit is pushed back rather than rewarded for leaving the view
        depth = np.maximum(local[..., 2], MIN_DEPTH)
        u = fx * local[..., 0] / depth + cx
        v = fy * local[..., 1] / depth + cy
        boxes = np.stack([u.min(axis=1), v.min(axis=1), u.max(axis=1), v.max(axis=1)], axis=1)  # (V, 4)
        edge = (boxes[view_idx, side_idx] - measured) / BOX_EDGE_SIGMA_PX
        extra = np.concatenate([(x[:3] - c0) / centre_sigma, [(x[4] - log_prior_h) / SIZE_PRIOR_SIGMA, (x[3] + x[5] - log_prior_area) / SIZE_PRIOR_SIGMA]])
        return np.concatenate([edge, extra])

    start_xz = math.sqrt(prior[0] * prior[2])
    x0 = np.concatenate([c0, np.log([start_xz, prior[1], start_xz])])
    fit = least_squares(residuals, x0, method="trf", x_scale=np.array([0.2, 0.2, 0.2, 0.3, 0.3, 0.3]))
    c, half = fit.x[:3], np.exp(fit.x[3:])
    return BoxEstimate(tuple(float(v) for v in c), tuple(float(v) for v in half), len(values))  # type: ignore[arg-type]

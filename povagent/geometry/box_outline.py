"""The 2D box around an axis-aligned 3D box as a camera sees it, also when part of it is behind.

The box is cut at the near plane (depth :data:`NEAR_PLANE`): what is left is a convex solid
whose corners are the box's corners in front of the camera and the points where the box's
twelve edges cross the near plane. Its outline is the 2D box around those points' projections,
exactly: a box the camera stands beside or inside is outlined by the part it can see. Used by
the perception simulator (what a detector would box), by the diagnostics (how far a point is
from the anchor) and by the training rationales (the anchor's box they state).
"""

from __future__ import annotations

import numpy as np

from povagent.geometry.camera import ViewCamera
from povagent.geometry.triangulation import optical_depth

#: Nearest depth (m) at which a box point still shows.
NEAR_PLANE = 0.05

#: Corner ``k`` takes the high value on axis ``a`` when bit ``a`` of ``k`` is set.
_CORNER_AT_HIGH = np.array([[bool(k & 1), bool(k & 2), bool(k & 4)] for k in range(8)])
#: The twelve edges as pairs of corner indices (corners differing in one bit).
_EDGES = np.array([(k, k | (1 << axis)) for k in range(8) for axis in range(3) if not k & (1 << axis)])


def outline(camera: ViewCamera, lo: np.ndarray, hi: np.ndarray) -> tuple[float, float, float, float] | None:
    """The 2D box (pixels, clipped to the image) around the projected axis-aligned box ``lo..hi``,
    from the part deeper than :data:`NEAR_PLANE`; ``None`` when nothing of it is in front or
    its outline in the image is thinner than a pixel."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    corners = np.where(_CORNER_AT_HIGH, hi, lo)
    depth = optical_depth(camera, corners)
    front = depth > NEAR_PLANE
    pts = corners[front]
    if not front.all():
        # where an edge crosses the near plane (depth is affine along the edge: exact)
        a, b = _EDGES[:, 0], _EDGES[:, 1]
        crossing = front[a] != front[b]
        a, b = a[crossing], b[crossing]
        t = (NEAR_PLANE - depth[a]) / (depth[b] - depth[a])
        pts = np.concatenate([pts, corners[a] + t[:, None] * (corners[b] - corners[a])])
    if not len(pts):
        return None
    px = camera.project_pixels(pts)
    w, h = camera.width - 1.0, camera.height - 1.0
    x0, y0 = np.clip(px[:, 0].min(), 0, w), np.clip(px[:, 1].min(), 0, h)
    x1, y1 = np.clip(px[:, 0].max(), 0, w), np.clip(px[:, 1].max(), 0, h)
    if x1 - x0 < 1.0 or y1 - y0 < 1.0:
        return None
    return (float(x0), float(y0), float(x1), float(y1))

"""The 2D box around an axis-aligned 3D box as a camera sees it, also when part of it is behind.

The box's twelve edges are sampled and only the samples in front of the camera (deeper than
:data:`NEAR_PLANE`) are projected, so a box the camera stands beside or inside is outlined by
the part it can see. Used by the perception simulator (what a detector would box) and by the
diagnostics (how far a point is from the anchor).
"""

from __future__ import annotations

import numpy as np

from povagent.geometry.camera import ViewCamera
from povagent.geometry.triangulation import optical_depth

#: Points per box edge sampled to outline a box that is partly behind the camera.
EDGE_SAMPLES = 16
#: Nearest depth (m) at which a box point still shows.
NEAR_PLANE = 0.05


def outline(camera: ViewCamera, lo: np.ndarray, hi: np.ndarray) -> tuple[float, float, float, float] | None:
    """The 2D box (pixels, clipped to the image) around the projected axis-aligned box ``lo..hi``
    (its edges sampled, so a box partly behind the camera is outlined by the part in front)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    t = np.linspace(0.0, 1.0, EDGE_SAMPLES)
    points = []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        for b0 in (lo[others[0]], hi[others[0]]):
            for b1 in (lo[others[1]], hi[others[1]]):
                p = np.empty((EDGE_SAMPLES, 3))
                p[:, axis] = lo[axis] + t * (hi[axis] - lo[axis])
                p[:, others[0]], p[:, others[1]] = b0, b1
                points.append(p)
    pts = np.concatenate(points)
    depth = optical_depth(camera, pts)
    pts = pts[depth > NEAR_PLANE]
    if not len(pts):
        return None
    px = camera.project_pixels(pts)
    w, h = camera.width - 1.0, camera.height - 1.0
    x0, y0 = np.clip(px[:, 0].min(), 0, w), np.clip(px[:, 1].min(), 0, h)
    x1, y1 = np.clip(px[:, 0].max(), 0, w), np.clip(px[:, 1].max(), 0, h)
    if x1 - x0 < 1.0 or y1 - y0 < 1.0:
        return None
    return (float(x0), float(y0), float(x1), float(y1))

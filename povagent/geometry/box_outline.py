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


def _edge_pattern() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For the 12 edges x EDGE_SAMPLES points: which coordinate runs along the edge, its
    fraction ``t``, and which fixed coordinates sit at the box's high corner."""
    t = np.linspace(0.0, 1.0, EDGE_SAMPLES)
    along, fraction, at_high = [], [], []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        for high0 in (False, True):
            for high1 in (False, True):
                for ti in t:
                    along.append([a == axis for a in range(3)])
                    fraction.append([ti if a == axis else 0.0 for a in range(3)])
                    at_high.append([(a == others[0] and high0) or (a == others[1] and high1) for a in range(3)])
    return np.array(along), np.array(fraction), np.array(at_high)


# computed once: every outline samples the same pattern of points on its box's edges
_ALONG, _T, _AT_HIGH = _edge_pattern()
_CORNER_AT_HIGH = np.array([[bool(k & 1), bool(k & 2), bool(k & 4)] for k in range(8)])


def outline(camera: ViewCamera, lo: np.ndarray, hi: np.ndarray) -> tuple[float, float, float, float] | None:
    """The 2D box (pixels, clipped to the image) around the projected axis-aligned box ``lo..hi``
    (its edges sampled, so a box partly behind the camera is outlined by the part in front)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    corners = np.where(_CORNER_AT_HIGH, hi, lo)
    if np.all(optical_depth(camera, corners) > NEAR_PLANE):
        # wholly in front: a projected box's outline is that of its projected corners (the
        # edges project to straight segments between them), no need to sample the edges
        pts = corners
    else:
        pts = np.where(_ALONG, lo + _T * (hi - lo), np.where(_AT_HIGH, hi, lo))
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

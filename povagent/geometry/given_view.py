"""Condition C (Given) in the image plane: the observer's own view, without its pose.

The observer view is taken by the observer, so the observer-relative directions are the
view's own (right is image right; front is towards the camera). What the image alone does not
give is scale and tilt; a virtual camera stands in for the unknown pose: at the observer's eye
height (:data:`EYE_HEIGHT`, the height of POVBench's observer views), facing straight ahead
(yaw 0), with the tilt that best explains the anchor's box given the anchor type's usual size
and centre height (:mod:`povagent.geometry.size_priors`). The anchor is then placed in that
virtual world, the target placed by the benchmark's rules, and projected back into the same
image, so errors of the assumed pose largely cancel. Pure: no files, no model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from povagent.geometry.camera import Camera
from povagent.geometry.placement import AnchorEstimate, place_target
from povagent.geometry.size_priors import SizePrior
from povagent.geometry.triangulation import CLIPPED_EDGE_PX, projected_box

#: Eye height (m) of the virtual observer: POVBench's observer views are taken at 1.55 m.
EYE_HEIGHT = 1.55
#: Tilts (degrees, positive looks down) the virtual camera may take.
TILT_RANGE = (-10.0, 70.0)
#: How much the box's centre weighs against the pointed centre: it averages two edges, each as
#: noisy as a pointed coordinate, so it is half as noisy (inverse-variance weighting).
BOX_CENTRE_WEIGHT = 2.0


def anchor_centre(centre_px: tuple[float, float], box: tuple[float, float, float, float] | None) -> tuple[float, float]:
    """The anchor's centre pixel from both answers: the pointed centre and, given a box, the
    box's centre, weighted :data:`BOX_CENTRE_WEIGHT` to 1 (the pointed centre alone without a box).

    With no pose to triangulate from, one view's pointing noise goes straight into the
    anchor's place; the box is a second, independent reading of the same centre.
    """
    if box is None:
        return centre_px
    w = BOX_CENTRE_WEIGHT
    bx, by = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0
    return ((centre_px[0] + w * bx) / (1.0 + w), (centre_px[1] + w * by) / (1.0 + w))


@dataclass(frozen=True)
class GivenViewSolution:
    """The target's pixel in the observer view, with the virtual camera's tilt and the anchor
    as reconstructed (``fitted`` says whether the box's edges chose the tilt)."""

    pixel: tuple[float, float]
    tilt_deg: float
    anchor: AnchorEstimate
    fitted: bool
    in_frame: bool


def _anchor_at(camera: Camera, centre_px: tuple[float, float], box: tuple[float, float, float, float] | None, prior: SizePrior) -> AnchorEstimate | None:
    centre = camera.point_on_plane(np.asarray(centre_px, dtype=float), plane_y=prior.centre_height)
    if not np.all(np.isfinite(centre)):
        return None
    w, _, d = prior.size
    if box is not None:
        depth = float(camera.to_camera(centre)[2])
        across = max(0.05, (box[2] - box[0]) * depth / camera.focal_px)
        # the box's width is the anchor's width or its depth, whichever way it faces the view
        along = d if abs(across - w) <= abs(across - d) else w
    else:
        across, along = w, d
    return AnchorEstimate(tuple(float(v) for v in centre), (across / 2.0, prior.half_height, along / 2.0))  # type: ignore[arg-type]


def _tilt_error(camera: Camera, anchor: AnchorEstimate, box: tuple[float, float, float, float]) -> float | None:
    predicted = projected_box(camera, np.asarray(anchor.centre), np.asarray(anchor.half))
    if predicted is None:
        return None
    errors = [predicted[k] - box[k] for k in (1, 3) if CLIPPED_EDGE_PX < box[k] < (camera.height - 1.0 - CLIPPED_EDGE_PX)]
    return float(np.mean(np.square(errors))) if errors else None


def solve_given_view(
    direction: str,
    anchor_type: str,
    prior: SizePrior,
    centre_px: tuple[float, float],
    box: tuple[float, float, float, float] | None,
    surface: str,
    width: int = 512,
    height: int = 512,
    fov: float = 100.0,
) -> GivenViewSolution:
    """The target's pixel in the observer view from the anchor's pointed centre and box (the
    anchor's centre is read from both, :func:`anchor_centre`)."""
    centre_px = anchor_centre(centre_px, box)

    def camera(tilt: float) -> Camera:
        return Camera((0.0, EYE_HEIGHT, 0.0), 0.0, tilt, fov, width, height)

    best: tuple[float, float] | None = None
    if box is not None:
        # coarse to fine: every 2 degrees, then every 0.25 around the best
        tilts = list(np.arange(TILT_RANGE[0], TILT_RANGE[1] + 1e-9, 2.0))
        for _pass in ("every 2 degrees", "every 0.25 around the best"):
            for tilt in tilts:
                cam = camera(float(tilt))
                anchor = _anchor_at(cam, centre_px, box, prior)
                err = _tilt_error(cam, anchor, box) if anchor is not None else None
                if err is not None and (best is None or err < best[0]):
                    best = (err, float(tilt))
            if best is None:
                break
            tilts = [t for t in np.arange(best[1] - 2.0, best[1] + 2.0 + 1e-9, 0.25) if TILT_RANGE[0] <= t <= TILT_RANGE[1]]
    fitted = best is not None
    tilt = best[1] if best is not None else _looking_at_centre_tilt(centre_px, prior, fov, width, height)
    cam = camera(tilt)
    anchor = _anchor_at(cam, centre_px, box, prior)
    if anchor is None:  # the centre's ray misses the prior height: put the anchor 2.5 m ahead
        ahead = cam.position + 2.5 * cam.ray(np.asarray(centre_px, dtype=float))
        anchor = AnchorEstimate(tuple(float(v) for v in ahead), (prior.size[0] / 2, prior.half_height, prior.size[2] / 2))  # type: ignore[arg-type]
    target = place_target(direction, anchor, anchor_type, cam.position, surface)
    u, v, depth = cam.project_point(target)
    if not depth > 1e-6:
        u, v = 0.5, 0.5
    inside = 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0
    x = min(max(u * width, 0.0), width - 1.0)
    y = min(max(v * height, 0.0), height - 1.0)
    return GivenViewSolution((x, y), tilt, anchor, fitted, inside)


def _looking_at_centre_tilt(centre_px: tuple[float, float], prior: SizePrior, fov: float, width: int, height: int) -> float:
    """Without a box: the tilt at which an anchor of usual height 2.5 m ahead shows where it
    was pointed at (a guess the solver reports)."""
    look = float(np.degrees(np.arctan2(EYE_HEIGHT - prior.centre_height, 2.5)))
    f = (height / 2.0) / np.tan(np.radians(fov) / 2.0)
    offset = float(np.degrees(np.arctan2(centre_px[1] - height / 2.0, f)))
    return float(np.clip(look - offset, *TILT_RANGE))

"""Where an object is in a frame, and how far a pointed pixel is from it: the perception probes'
error (an addition, docs/how-to/why-models-fail.md).

An object's extent in a frame is the 2D box (normalized, clipped to the image) around the part
of its axis-aligned box in front of the camera (:func:`~povagent.geometry.box_outline.outline`,
what a detector would box), and its centre as the official metric places a point
(:func:`~povagent.scoring.normalized_l2.official_uv`: clamped, behind the camera at the image
centre). The diagnostics' anchor step measures from the anchor's extent; the ``probe-anchor``
and ``probe-observer`` scorers give a pointed pixel's distance to the probed object's box and
centre, in the official metric's normalized units. Pure: no file, no clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from povagent.dataset.instances import Frame
from povagent.dataset.release_models import SceneObject
from povagent.geometry.box_outline import outline
from povagent.scoring.normalized_l2 import clamp_unit, official_uv


@dataclass(frozen=True)
class ObjectExtent:
    """Where an object is in one frame: ``box`` (normalized ``x0, y0, x1, y1``) around the part
    of it in front of the camera and in the image, ``None`` when no part is; ``centre`` its box
    centre as the official metric places a point."""

    box: tuple[float, float, float, float] | None
    centre: tuple[float, float]

    def box_distance(self, u: float, v: float) -> float | None:
        """Normalized distance from ``(u, v)`` (clamped fractions) to the box, 0 inside it
        (``None`` without a box)."""
        if self.box is None:
            return None
        x0, y0, x1, y1 = self.box
        dx = max(x0 - u, 0.0, u - x1)
        dy = max(y0 - v, 0.0, v - y1)
        return math.hypot(dx, dy)

    def distance(self, u: float, v: float) -> float:
        """The distance to the box, or to the centre when no part of the object is in the image."""
        d = self.box_distance(u, v)
        return math.hypot(u - self.centre[0], v - self.centre[1]) if d is None else d


def object_extent(obj: SceneObject, frame: Frame) -> ObjectExtent:
    """The extent of ``obj`` in ``frame`` (see :class:`ObjectExtent`)."""
    cam = frame.camera
    box = obj.raw_metadata.axisAlignedBoundingBox
    corners = np.asarray(box.cornerPoints, dtype=float)
    seen = outline(cam, corners.min(axis=0), corners.max(axis=0))
    centre = official_uv(np.asarray(box.center.as_tuple(), dtype=float), frame)
    if seen is None:
        return ObjectExtent(None, centre)
    return ObjectExtent((seen[0] / cam.width, seen[1] / cam.height, seen[2] / cam.width, seen[3] / cam.height), centre)


def pointing_error(obj: SceneObject, frame: Frame, x: float, y: float, seen: bool) -> dict[str, Any]:
    """A probe's scores for the pixel ``(x, y)`` pointed at ``obj`` in ``frame`` (clamped to the
    image, as officially): ``box_error`` (0 inside the box; ``None`` when no part of the object
    is in the image), ``inside_box``, ``centre_error``, ``in_view`` (some part in the image) and
    ``seen`` (the frame's record lists the object, as the caller says)."""
    cam = frame.camera
    u, v = clamp_unit(x / cam.width), clamp_unit(y / cam.height)
    extent = object_extent(obj, frame)
    box_error = extent.box_distance(u, v)
    return {
        "answered": True,
        "object_type": obj.object_type,
        "seen": seen,
        "in_view": extent.box is not None,
        "inside_box": box_error == 0.0 if box_error is not None else None,
        "box_error": box_error,
        "centre_error": math.hypot(u - extent.centre[0], v - extent.centre[1]),
    }

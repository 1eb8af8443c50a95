"""The relation region: every place a 0.4 m target could stand and still satisfy the sentence.

The official metric scores one canonical point; the paper's Limitations note that it "may
penalize alternative placements that satisfy the intended spatial relation". This module
samples those alternatives with the paper's own rules, widened in two documented ways, and
tests a predicted pixel against their image:

* **left / right / front** beside the anchor: the rule's boundary placement
  ``b(d') + (0.2 + gap) d'`` (:func:`~povagent.geometry.ground_truth.boundary_points`, the
  official rule for many directions at once) for every direction ``d'`` within :data:`SECTOR_HALF_ANGLE` (45 degrees)
  of the observer-relative direction ``d`` (the half-plane quadrant a person still calls "to
  the left") and every gap between the cube and the anchor from 0 to :data:`MAX_GAP` (0.5 m:
  "next to", not "somewhere on that side of the room"), at the official height
  ``y_surf + 0.2`` (the same supporting surface);
* **left / right on a flat-topped anchor** (the rule's ``c + 0.2 d`` case): the cube on the
  anchor's top, its centre ``c + s d'`` with ``d'`` in the same sector and ``s`` from
  :data:`MIN_ON_TOP_OFFSET` (0.1 m: nearer the centre it is "on", not "left on") to the top's
  edge along ``d'`` (at least the official 0.2 m), at ``top + 0.2``;
* **up**: the cube's centre anywhere over the anchor's top rectangle, at ``top + 0.2``;
* a direction whose verdict is not ``appropriate`` has only its raw placement.

The ground truth is always one of the samples. Samples are spaced at most about 0.1 m apart
(5 degree steps, 0.1 m gaps), finer than the cube, over at most :data:`MAX_STEPS` steps a side:
beyond 10 m (no furniture is that large; ``validate`` refuses boxes over
:data:`~povagent.dataset.release_models.MAX_OBJECT_SIDE_M`) the spacing grows instead, so one
instance's samples stay bounded (about 10,000 over a top) whatever a dataset says. In a frame, each sample in front of the
camera becomes a disc of the cube's projected half-size (``f * 0.2 / depth`` pixels) plus
:data:`PIXEL_TOLERANCE` (4 px); the region is their union, i.e. the image area the cube would
cover at some valid placement, except that a sample nearer than :data:`DISC_DEPTH_FLOOR`
(0.5 m) keeps the disc it would have there (a nearer cube fills the frame, and one such disc
would make the whole image "valid"). A sample behind the camera is left out, so a frame that
sees no valid placement has an empty region (nothing in it satisfies the relation). Sample centres outside the image are clamped to its
border, as the official metric clamps the ground truth and the answer (an answer is clamped
too). Walls are not modelled (the release carries no floor plan).

Pure geometry: no file, no clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from povagent.geometry.camera import Camera
from povagent.geometry.directions import direction_spec
from povagent.geometry.ground_truth import (
    TARGET_HALF_SIZE,
    PlacementCase,
    boundary_points,
    direction_vectors,
    stands_on_anchor,
    surface_height,
)

#: Directions up to this angle (degrees) from the observer-relative one still satisfy the relation.
SECTOR_HALF_ANGLE = 45.0
#: Angular step (degrees) of the sampled directions.
ANGLE_STEP = 5.0
#: The largest gap (m) between the target cube and the anchor's box that still reads as "beside".
MAX_GAP = 0.5
#: Step (m) of the sampled gaps and of the grid over the anchor's top.
DISTANCE_STEP = 0.1
#: At most this many steps along one side of a sampled range: the bound on one instance's
#: samples (time and memory grew with the square of the anchor's size: a 300 m anchor took 5 s
#: and 1.3 GB). 10 m of furniture at :data:`DISTANCE_STEP`; larger ranges are sampled coarser.
MAX_STEPS = 100
#: A target on the anchor's top stands at least this far (m) from the top's centre towards its side.
MIN_ON_TOP_OFFSET = 0.1
#: Pixels added to each sample's projected cube half-size: pointing slack at far, small regions.
PIXEL_TOLERANCE = 4.0
#: Depth (m) at or below which a sample counts as behind the camera.
NEAR_PLANE = 0.05
#: A sample nearer than this (m) gets the disc it would have here: a 0.4 m cube at 0.5 m already
#: spans a third of a 512 px, 100 degree frame (86 px radius), and nearer samples' discs would
#: cover the whole image.
DISC_DEPTH_FLOOR = 0.5


def _sector(d: np.ndarray) -> np.ndarray:
    """The directions ``(K, 3)`` within :data:`SECTOR_HALF_ANGLE` of ``d``, every :data:`ANGLE_STEP`
    degrees (``d`` turned about +y by each angle), from the most clockwise to the most
    counter-clockwise."""
    n = int(round(SECTOR_HALF_ANGLE / ANGLE_STEP))
    angles = [math.radians(k * ANGLE_STEP) for k in range(-n, n + 1)]
    c = np.array([math.cos(a) for a in angles])
    s = np.array([math.sin(a) for a in angles])
    return np.stack([d[0] * c - d[2] * s, np.zeros_like(c), d[0] * s + d[2] * c], axis=1)


def _steps(lo: float, hi: float) -> list[float]:
    """``lo`` to ``hi`` in equal steps of at most :data:`DISTANCE_STEP` (both ends included),
    and at most :data:`MAX_STEPS` steps."""
    n = min(MAX_STEPS, max(1, int(math.ceil((hi - lo) / DISTANCE_STEP - 1e-9))))
    return [lo + (hi - lo) * k / n for k in range(n + 1)]


def valid_placements(case: PlacementCase) -> np.ndarray:
    """Centres ``(N, 3)`` of the 0.4 m target cube wherever it satisfies the case's relation
    (the ground truth first); see the module docstring for the rules."""
    truth = case.target()
    if not case.rules_apply:
        return truth[None, :]
    box = case.box
    cx, cz = box.center_xz
    points: list[tuple[float, float, float]] = [(float(truth[0]), float(truth[1]), float(truth[2]))]
    spec = direction_spec(case.direction)
    if spec is not None and spec.vertical:
        hx, hz = box.half_xz
        y = box.top + TARGET_HALF_SIZE
        points += [(x, y, z) for z in _steps(cz - hz, cz + hz) for x in _steps(cx - hx, cx + hx)]
        return np.array(points)
    d = direction_vectors(np.asarray(case.anchor_position, dtype=float), np.asarray(case.observer_position, dtype=float)).get(case.direction)
    if d is None or math.hypot(d[0], d[2]) < 1e-6:
        return truth[None, :]
    on_anchor = stands_on_anchor(case.direction, case.anchor_type, case.surface)
    sector = _sector(d)
    bx, bz = boundary_points(box, sector)
    if on_anchor:
        y = box.top + TARGET_HALF_SIZE
        for k, (ddx, ddz) in enumerate(zip(sector[:, 0].tolist(), sector[:, 2].tolist())):
            edge = max(math.hypot(float(bx[k]) - cx, float(bz[k]) - cz), 2 * MIN_ON_TOP_OFFSET)
            points += [(cx + s * ddx, y, cz + s * ddz) for s in _steps(MIN_ON_TOP_OFFSET, edge)]
        return np.array(points, dtype=float)
    y = surface_height(case.surface, box) + TARGET_HALF_SIZE
    offsets = np.array([TARGET_HALF_SIZE + g for g in _steps(0.0, MAX_GAP)])
    # every (direction, gap) in the order of a loop over directions, then gaps
    xs = (bx[:, None] + offsets[None, :] * sector[:, 0, None]).ravel()
    zs = (bz[:, None] + offsets[None, :] * sector[:, 2, None]).ravel()
    beside = np.stack([xs, np.full_like(xs, y), zs], axis=1)
    return np.concatenate([np.array(points, dtype=float), beside])


@dataclass(frozen=True)
class RelationRegion:
    """The relation region in one frame: sample discs (pixel centres and radii)."""

    centres: np.ndarray
    radii: np.ndarray
    width: int
    height: int

    @property
    def empty(self) -> bool:
        """No valid placement is in front of the camera."""
        return self.centres.shape[0] == 0

    def margin(self, x: float, y: float) -> float | None:
        """How far (px) the pixel ``(x, y)``, clamped to the image as the official metric
        clamps, lies outside the region (negative: inside); ``None`` for an empty region."""
        if self.empty:
            return None
        px = min(max(x, 0.0), float(self.width)) if x == x else x
        py = min(max(y, 0.0), float(self.height)) if y == y else y
        dist = np.hypot(self.centres[:, 0] - px, self.centres[:, 1] - py) - self.radii
        value = float(dist.min())
        return value if value == value else None

    def contains(self, x: float, y: float) -> bool:
        """True when the (clamped) pixel lies in the region."""
        m = self.margin(x, y)
        return m is not None and m <= 0.0


def region_in_frame(placements: np.ndarray, camera: Camera) -> RelationRegion:
    """The image region of the valid ``placements`` seen by ``camera`` (see the module docstring)."""
    cam = camera.to_camera(placements)
    depth = cam[:, 2]
    keep = depth > NEAR_PLANE
    cam, depth = cam[keep], depth[keep]
    f = camera.focal_px
    u = f * cam[:, 0] / depth + camera.width / 2.0
    v = camera.height / 2.0 - f * cam[:, 1] / depth
    radii = f * TARGET_HALF_SIZE / np.maximum(depth, DISC_DEPTH_FLOOR) + PIXEL_TOLERANCE
    # clamped into the image as the official metric clamps the ground truth (the answer is too)
    centres = np.stack([np.clip(u, 0.0, camera.width), np.clip(v, 0.0, camera.height)], axis=1)
    return RelationRegion(centres, radii, camera.width, camera.height)

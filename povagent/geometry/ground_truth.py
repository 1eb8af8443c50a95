"""Ground-truth target points: the surface-corrected placement rules of the official scorer.

Directions live in the xz plane and are defined from the observer facing the anchor:
``fwd`` points from the observer camera to the anchor (y zeroed), ``right = up x fwd``,
``left = -right``, ``front = -fwd`` (towards the observer). Which axis and sign each direction
takes, whether it stands on the anchor's top and whether it may stand on a flat-topped anchor
come from the directions registry (:mod:`povagent.geometry.directions`); this module applies
them. The target is a 0.4 m cube, hence the 0.2 m offsets. Only a direction whose surface
verdict is ``"appropriate"`` is corrected; any other verdict keeps the raw
``placements[dir].position`` of the release.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from povagent.geometry.directions import DIRECTION_REGISTRY, Axis, direction_spec

#: Anchors with a flat top where a left/right target may stand on the anchor itself.
FLAT_TOPPED_ANCHORS = frozenset(
    {"Bed", "CounterTop", "Desk", "Desktop", "DiningTable", "Dresser", "SideTable"}
)

#: Half the 0.4 m target cube.
TARGET_HALF_SIZE = 0.2

#: Distance used by the boundary rule when a direction has no xz component at all.
DEGENERATE_BOUNDARY_DISTANCE = 0.3

#: How a surface phrase names an anchor type (the official scorer's keyword table).
ANCHOR_KEYWORDS: dict[str, tuple[str, ...]] = {
    "Bed": ("bed",),
    "CounterTop": ("counter", "countertop"),
    "Desk": ("desk",),
    "Desktop": ("desktop",),
    "DiningTable": ("dining table",),
    "Dresser": ("dresser",),
    "SideTable": ("side table",),
    "ArmChair": ("armchair", "arm chair"),
    "Chair": ("chair",),
    "CoffeeTable": ("coffee table",),
    "Sofa": ("sofa", "couch"),
    "Fridge": ("fridge", "refrigerator"),
    "Sink": ("sink",),
    "Toilet": ("toilet",),
    "WashingMachine": ("washing machine",),
}

#: Below this length a direction component (or the observer-to-anchor vector) counts as zero,
#: as in the official scorer.
ZERO_LENGTH = 1e-6


def anchor_keywords(object_type: str) -> tuple[str, ...]:
    """Lower-case words by which a surface phrase can name ``object_type``.

    Types outside the table are split at capitals only (``TVStand`` -> ``t v stand``), the way
    the official scorer splits them: lower-case runs and digits that do not follow a capital are
    dropped, so an empty type yields the empty keyword, which every phrase contains.
    """
    if object_type in ANCHOR_KEYWORDS:
        return ANCHOR_KEYWORDS[object_type]
    return (" ".join(re.findall(r"[A-Z][a-z]*", object_type)).lower(),)


def surface_names_anchor(surface: str, anchor_type: str) -> bool:
    """True when the lower-cased surface phrase mentions the anchor type by keyword."""
    text = surface.lower()
    return any(k in text for k in anchor_keywords(anchor_type))


@dataclass(frozen=True)
class AnchorBox:
    """The anchor's axis-aligned box as the scorer uses it: xz centre, xz half sizes, top y."""

    center_xz: tuple[float, float]
    half_xz: tuple[float, float]
    top: float


def direction_vectors(anchor_position: np.ndarray, observer_position: np.ndarray) -> dict[str, np.ndarray]:
    """Unit xz vectors (as 3-vectors, y = 0) of every ``beside`` direction from the observer's view.

    ``fwd = normalize(anchor - observer)`` with y zeroed; ``right = world_up x fwd`` (in this
    left-handed frame that is ``(fwd_z, 0, -fwd_x)``); ``front = -fwd``. As officially, a
    vector no longer than 1e-6 is left as it is rather than normalized (an anchor straight
    below the observer gives zero directions: the target then sits at the anchor's centre).
    """
    d = np.asarray(anchor_position, dtype=float) - np.asarray(observer_position, dtype=float)
    fwd = np.array([d[0], 0.0, d[2]])
    n = math.hypot(fwd[0], fwd[2])
    if n > ZERO_LENGTH:
        fwd = fwd / n
    # world_up x fwd written out: np.cross on 3-vectors costs ~10 us, and every instance of a
    # dataset calls this when the instances are built
    right = np.array([fwd[2], 0.0, -fwd[0]])
    rn = math.hypot(right[0], right[2])
    if rn > ZERO_LENGTH:
        right = right / rn
    basis = {Axis.SIDE: right, Axis.FORWARD: fwd}
    return {spec.name: spec.axis[1] * basis[spec.axis[0]] for spec in DIRECTION_REGISTRY if spec.axis is not None}


def may_stand_on(direction: str, anchor_type: str) -> bool:
    """True when a target in ``direction`` may stand on the anchor itself: the direction allows
    it (left, right) and the anchor is flat-topped."""
    spec = direction_spec(direction)
    return spec is not None and spec.may_stand_on_anchor and anchor_type in FLAT_TOPPED_ANCHORS


def stands_on_anchor(direction: str, anchor_type: str, surface: str | None) -> bool:
    """True when the rule puts the target on the anchor's top: always for an ``on_top``
    direction (up); for one that :func:`may_stand_on` a flat-topped anchor, when the surface
    judgement names the anchor; never otherwise."""
    spec = direction_spec(direction)
    if spec is None:
        return False
    if spec.vertical:
        return True
    return may_stand_on(direction, anchor_type) and surface is not None and surface_names_anchor(surface, anchor_type)


def boundary_point(box: AnchorBox, direction: np.ndarray) -> np.ndarray:
    """Where the ray from the box's xz centre along ``direction`` leaves the box (x, z)."""
    dx, dz = float(direction[0]), float(direction[2])
    hx, hz = box.half_xz
    ts = []
    if abs(dx) > ZERO_LENGTH:
        ts.append(hx / abs(dx))
    if abs(dz) > ZERO_LENGTH:
        ts.append(hz / abs(dz))
    t = min(ts) if ts else DEGENERATE_BOUNDARY_DISTANCE
    cx, cz = box.center_xz
    return np.array([cx + t * dx, cz + t * dz])


def boundary_points(box: AnchorBox, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`boundary_point` of every direction ``(K, 3)`` at once, as ``(x, z)`` arrays of ``K``:
    the same rule, each number computed by the same operations in the same order, so the
    same bits (``tests/geometry/test_boundary_points.py`` holds the two together)."""
    dx, dz = directions[:, 0], directions[:, 2]
    hx, hz = box.half_xz
    ax, az = np.abs(dx), np.abs(dz)
    with np.errstate(divide="ignore"):
        tx = np.where(ax > ZERO_LENGTH, hx / np.where(ax > ZERO_LENGTH, ax, 1.0), np.inf)
        tz = np.where(az > ZERO_LENGTH, hz / np.where(az > ZERO_LENGTH, az, 1.0), np.inf)
    t = np.minimum(tx, tz)
    t = np.where(np.isinf(t), DEGENERATE_BOUNDARY_DISTANCE, t)
    cx, cz = box.center_xz
    return cx + t * dx, cz + t * dz


def surface_height(surface: str | None, box: AnchorBox) -> float:
    """``0`` for a floor surface, otherwise the anchor's top.

    When the surface names another object the release has no box for it, so the anchor's top
    stands in for it, exactly as the official scorer does.
    """
    if surface is not None and "floor" in surface.lower():
        return 0.0
    return box.top


def target_point(
    direction: str,
    box: AnchorBox,
    anchor_type: str,
    anchor_position: np.ndarray,
    observer_position: np.ndarray,
    verdict: str | None,
    surface: str | None,
    raw_placement: np.ndarray,
) -> np.ndarray:
    """The 3D ground-truth point for one (pair, direction).

    ``observer_position`` is the observer camera's position (``camera.cam_pos``);
    ``anchor_type`` is the pair's ``landmark_type``. A direction the rules do not know keeps
    its raw placement, as officially.
    """
    if verdict != "appropriate":
        return np.asarray(raw_placement, dtype=float)
    cx, cz = box.center_xz
    spec = direction_spec(direction)
    if spec is not None and spec.vertical:
        return np.array([cx, box.top + TARGET_HALF_SIZE, cz])
    d = direction_vectors(anchor_position, observer_position).get(direction)
    if d is None:
        return np.asarray(raw_placement, dtype=float)
    if stands_on_anchor(direction, anchor_type, surface):
        return np.array(
            [cx + TARGET_HALF_SIZE * d[0], box.top + TARGET_HALF_SIZE, cz + TARGET_HALF_SIZE * d[2]]
        )
    bx, bz = boundary_point(box, d)
    y = surface_height(surface, box) + TARGET_HALF_SIZE
    return np.array([bx + TARGET_HALF_SIZE * d[0], y, bz + TARGET_HALF_SIZE * d[2]])


@dataclass(frozen=True)
class PlacementCase:
    """Everything the placement rules read for one (pair, direction): the inputs of
    :func:`target_point`, kept together so the ground truth and its counterfactuals
    (:mod:`povagent.geometry.counterfactual`) are computed from the same record.

    ``anchor_centre`` is the anchor's AABB centre (x, y, z); ``observer_position`` the observer
    camera's position; ``verdict``, ``surface`` and ``raw_placement`` come from the release.
    """

    direction: str
    box: AnchorBox
    anchor_type: str
    anchor_position: tuple[float, float, float]
    anchor_centre: tuple[float, float, float]
    observer_position: tuple[float, float, float]
    verdict: str | None
    surface: str | None
    raw_placement: tuple[float, float, float]

    @property
    def rules_apply(self) -> bool:
        """True when the surface-corrected rules place the target (verdict ``appropriate``);
        otherwise the raw placement stands, for the ground truth and every counterfactual."""
        return self.verdict == "appropriate"

    def target(self, direction: str | None = None, observer_position: np.ndarray | None = None) -> np.ndarray:
        """The rules' target for ``direction`` (default: the case's) seen from
        ``observer_position`` (default: the observer camera): :func:`target_point` itself."""
        return target_point(
            direction or self.direction,
            self.box,
            self.anchor_type,
            np.asarray(self.anchor_position, dtype=float),
            np.asarray(self.observer_position if observer_position is None else observer_position, dtype=float),
            self.verdict,
            self.surface,
            np.asarray(self.raw_placement, dtype=float),
        )

"""The scene facts a rationale states, computed from the geometry of one instance.

Pure functions of an :class:`~povagent.dataset.instances.Instance` and its pair entry: which
frame shows the target best (and whether the observer's furniture and the anchor are in it), where
the anchor and the furniture are in that frame, which way the observer faces relative to the
camera, which way the direction points in the image, and the ground-truth pixel. A rationale
is text around these facts; the fact-check test recomputes each of them independently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from povagent.dataset.instances import Frame, Instance
from povagent.dataset.models import Direction, PairEntry
from povagent.geometry.camera import BEHIND_EPSILON, Camera
from povagent.geometry.ground_truth import direction_vectors

#: How the observer faces relative to the camera, by the angle between the observer's facing
#: (furniture -> anchor, on the floor plane) and the camera's forward: within 45 degrees "away",
#: beyond 135 "towards", otherwise to the image's left or right.
FACINGS = ("away from the camera", "towards the camera", "towards the image's left", "towards the image's right")

#: Words for where a point sits across the image, by thirds of the width.
COLUMNS = ("left", "centre", "right")

#: The relation words of the S-CoT prompt's step 4a, by direction.
RELATION_WORDS: dict[Direction, str] = {
    Direction.LEFT: "LEFT",
    Direction.RIGHT: "RIGHT",
    Direction.FRONT: "FRONT",
    Direction.UP: "ON TOP",
}

#: Metres moved along a direction to read which way it points in the image.
DIRECTION_PROBE_M = 0.5


#: How many other views of the anchor a rationale names.
OTHER_VIEWS = 2


class NoTeachingFrame(ValueError):
    """No frame of an Inferred/Stated instance shows the anchor with the target inside it."""


@dataclass(frozen=True)
class PixelBox:
    """A box in pixels: ``x0 <= x1``, ``y0 <= y1``, clipped to the image."""

    x0: int
    y0: int
    x1: int
    y1: int


@dataclass(frozen=True)
class InstanceFacts:
    """Everything a rationale may state about one instance, each computed from the scene.

    ``frame_index`` is ``None`` for Given (the observer view is the only image). Pixels are in
    the frame's own pixel grid, origin top-left; ``answer_xy`` is the ground truth's exact pixel
    (``u * W, v * H``, as the official scorer compares it).
    """

    instance_id: str
    condition: str
    direction: Direction
    frame_index: int | None
    frame_path: str
    frame_size: tuple[int, int]
    observer_type: str
    anchor_type: str
    observer_visible: bool
    anchor_visible: bool
    anchor_xy: tuple[float, float]
    anchor_box: PixelBox | None
    observer_xy: tuple[float, float] | None
    observer_column: str | None
    facing: str
    relation: str
    image_direction: str
    surface: str
    answer_xy: tuple[float, float]
    #: Other frames that saw the anchor, with its centre's pixel there: ``(frame index, (x, y))``,
    #: at most :data:`OTHER_VIEWS`, widest baseline first (a second view fixes the anchor's depth).
    anchor_other_views: tuple[tuple[int, tuple[float, float]], ...] = ()

    def answer_pixel(self) -> tuple[int, int]:
        """The answer in whole pixels, inside ``[0, W-1] x [0, H-1]``."""
        w, h = self.frame_size
        x, y = self.answer_xy
        return (min(max(int(round(x)), 0), w - 1), min(max(int(round(y)), 0), h - 1))


def gt_pixel(camera: Camera, target: tuple[float, float, float]) -> tuple[float, float] | None:
    """The ground truth's pixel in ``camera`` when it lies in front of it and inside the image."""
    u, v, depth = camera.project_point(target)
    if not depth > BEHIND_EPSILON or not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
        return None
    return (u * camera.width, v * camera.height)


def teaching_frame(instance: Instance) -> Frame:
    """The frame an Inferred/Stated answer names: the target inside it, the anchor seen in it.

    Among frames whose exploration record saw the anchor and where the ground truth projects
    inside the image, frames that also saw the observer's furniture come first, then the one
    whose ground truth lies nearest the image centre (ties: the lower index). Raises
    :class:`NoTeachingFrame` when no frame qualifies.
    """
    anchor_id = instance.anchor_object.objectId
    observer_id = instance.observer_object.objectId
    best: tuple[int, float, int] | None = None
    for frame in instance.frames:
        if anchor_id not in frame.in_frame_hits:
            continue
        pixel = gt_pixel(frame.camera, instance.target)
        if pixel is None:
            continue
        w, h = frame.camera.width, frame.camera.height
        off_centre = math.hypot(pixel[0] / w - 0.5, pixel[1] / h - 0.5)
        key = (0 if observer_id in frame.in_frame_hits else 1, off_centre, frame.index)
        if best is None or key < best:
            best = key
    if best is None:
        raise NoTeachingFrame(f"{instance.id}: no frame shows the anchor with the target inside it")
    return instance.frames[best[2]]


def facing_relative_to(camera: Camera, observer_xz: np.ndarray, anchor_xz: np.ndarray) -> str:
    """Which way an observer at ``observer_xz`` facing ``anchor_xz`` looks, seen from ``camera``."""
    d = anchor_xz - observer_xz
    yaw = math.radians(camera.yaw)
    ahead = d[0] * math.sin(yaw) + d[1] * math.cos(yaw)  # along the camera's forward on the floor
    across = d[0] * math.cos(yaw) - d[1] * math.sin(yaw)  # along the camera's right
    angle = math.degrees(math.atan2(across, ahead))
    if abs(angle) <= 45.0:
        return FACINGS[0]
    if abs(angle) >= 135.0:
        return FACINGS[1]
    return FACINGS[3] if angle > 0 else FACINGS[2]


def image_direction(du: float, dv: float) -> str:
    """Eight-way words for an image-space step ``(du, dv)`` (v grows downwards)."""
    angle = math.degrees(math.atan2(-dv, du)) % 360.0  # 0 = right, 90 = up the image
    names = ("right", "upper right", "top", "upper left", "left", "lower left", "bottom", "lower right")
    return names[int(((angle + 22.5) % 360.0) // 45.0)]


def _column(x: float, width: int) -> str:
    return COLUMNS[min(int(3 * x / width), 2)] if 0 <= x <= width else ("left" if x < 0 else "right")


def _clip_box(points: np.ndarray, width: int, height: int) -> PixelBox | None:
    """The pixel box of projected corner points (NaN where behind), clipped to the image."""
    finite = points[np.isfinite(points).all(axis=1)]
    if len(finite) == 0:
        return None
    x0, y0 = np.clip(finite.min(axis=0), 0, [width - 1, height - 1])
    x1, y1 = np.clip(finite.max(axis=0), 0, [width - 1, height - 1])
    if x1 <= x0 or y1 <= y0:
        return None
    return PixelBox(int(math.floor(x0)), int(math.floor(y0)), int(math.ceil(x1)), int(math.ceil(y1)))


def _pixel(camera: Camera, point: tuple[float, float, float]) -> tuple[float, float] | None:
    u, v, depth = camera.project_point(point)
    if not depth > BEHIND_EPSILON:
        return None
    return (u * camera.width, v * camera.height)


def surface_phrase(pair: PairEntry, direction: Direction) -> str:
    """Where the target rests, as the stage-3 judgement says (``on the floor`` when it is silent)."""
    judgement = pair.stage3.get(direction)
    surface = (judgement.surface if judgement and judgement.verdict == "appropriate" else None) or "on the floor"
    return surface.strip()


def instance_facts(instance: Instance, pair: PairEntry) -> InstanceFacts:
    """The facts of ``instance`` (its pair entry ``pair`` gives the surface judgement).

    Raises :class:`NoTeachingFrame` for an Inferred/Stated instance no frame can teach, and for
    a Given instance whose ground truth is outside the observer view (no correct pixel exists).
    """
    if instance.condition.uses_exploration_frames:
        frame = teaching_frame(instance)
        frame_index: int | None = frame.index
    else:
        frame = instance.frames[0]
        frame_index = None
    camera = frame.camera
    w, h = camera.width, camera.height
    answer = gt_pixel(camera, instance.target)
    if answer is None:
        raise NoTeachingFrame(f"{instance.id}: the target is outside the observer view")
    box = instance.anchor_object.raw_metadata.axisAlignedBoundingBox
    corners = camera.project_pixels(np.asarray(box.cornerPoints, dtype=float))
    anchor_centre = (box.center.x, box.center.y, box.center.z)
    anchor_xy = _pixel(camera, anchor_centre) or (w / 2.0, h / 2.0)
    observer_pos = instance.observer_object.position.as_tuple()
    observer_xy = _pixel(camera, observer_pos)
    observer_cam = np.asarray(instance.observer_camera.position, dtype=float)
    anchor_pos = np.asarray(instance.anchor_object.position.as_tuple(), dtype=float)
    facing = facing_relative_to(camera, observer_cam[[0, 2]], anchor_pos[[0, 2]])
    # which way the direction points in this image: step from the target's resting point
    if instance.direction is Direction.UP:
        step = np.array([0.0, DIRECTION_PROBE_M, 0.0])
    else:
        step = DIRECTION_PROBE_M * direction_vectors(anchor_pos, observer_cam)[instance.direction.value]
    start = np.array([box.center.x, instance.target[1], box.center.z])
    p0, p1 = camera.project_pixels(np.stack([start, start + step]))
    if np.isfinite(p0).all() and np.isfinite(p1).all():
        towards = image_direction(float(p1[0] - p0[0]), float(p1[1] - p0[1]))
    else:
        towards = "out of view"
    other_views: tuple[tuple[int, tuple[float, float]], ...] = ()
    if frame_index is not None:
        candidates = []
        for other in instance.frames:
            if other.index == frame_index or instance.anchor_object.objectId not in other.in_frame_hits:
                continue
            pixel = gt_pixel(other.camera, anchor_centre)
            if pixel is None:
                continue
            baseline = math.dist(other.camera.position, camera.position)
            candidates.append((-baseline, other.index, pixel))
        other_views = tuple((i, p) for _, i, p in sorted(candidates)[:OTHER_VIEWS])
    observer_visible = instance.observer_object.objectId in frame.in_frame_hits if frame_index is not None else bool(
        observer_xy and 0 <= observer_xy[0] <= w and 0 <= observer_xy[1] <= h
    )
    anchor_visible = instance.anchor_object.objectId in frame.in_frame_hits if frame_index is not None else True
    return InstanceFacts(
        instance_id=instance.id,
        condition=instance.condition.value,
        direction=instance.direction,
        frame_index=frame_index,
        frame_path=frame.image_path,
        frame_size=(w, h),
        observer_type=instance.observer_object.object_type,
        anchor_type=instance.anchor_object.object_type,
        observer_visible=observer_visible,
        anchor_visible=anchor_visible,
        anchor_xy=anchor_xy,
        anchor_box=_clip_box(corners, w, h),
        observer_xy=observer_xy,
        observer_column=_column(observer_xy[0], w) if observer_xy is not None else None,
        facing=facing,
        relation=RELATION_WORDS[instance.direction],
        image_direction=towards,
        surface=surface_phrase(pair, instance.direction),
        answer_xy=answer,
        anchor_other_views=other_views,
    )

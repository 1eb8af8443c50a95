"""The scene facts a rationale states, computed from the geometry of one instance.

Pure functions of an :class:`~povagent.dataset.instances.Instance` and its pair entry: which
frame shows the target best (and whether the observer's furniture and the anchor are in it), where
the anchor and the furniture are in that frame, which way the observer faces relative to the
camera (and where the speaker stood, which is what the ground truth's directions depend on),
which way the direction points in the image, and the ground-truth pixel. A rationale is text
around these facts; the fact-check test recomputes each of them independently. They stand with
the tasks because a generated relation question reads them too (the training export sits above).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import DIRECTIONS, Direction, PairEntry, SceneObject
from povagent.geometry.box_outline import outline
from povagent.geometry.camera import BEHIND_EPSILON, Camera
from povagent.geometry.directions import spec_of
from povagent.geometry.ground_truth import direction_vectors

#: How the observer faces relative to the camera, by the angle between the observer's facing
#: (furniture -> anchor, on the floor plane) and the camera's forward: within 45 degrees "away",
#: beyond 135 "towards", otherwise to the image's left or right.
FACINGS = ("away from the camera", "towards the camera", "towards the image's left", "towards the image's right")

#: Words for where a point sits across the image, by thirds of the width.
COLUMNS = ("left", "centre", "right")

#: The relation words of the S-CoT prompt's step 4a, by direction.
RELATION_WORDS: dict[Direction, str] = {d: spec_of(d).prompt_word for d in DIRECTIONS}

#: Metres moved along a direction to read which way it points in the image.
DIRECTION_PROBE_M = 0.5


#: How many other views of the anchor a rationale names.
OTHER_VIEWS = 3


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
class AnchorView:
    """Another frame that saw the anchor: its index, the anchor's centre pixel and its box there."""

    frame_index: int
    xy: tuple[float, float]
    box: PixelBox | None


@dataclass(frozen=True)
class InstanceFacts:
    """Everything a rationale may state about one instance, each computed from the scene.

    ``frame_index`` is ``None`` for Given (the observer view is the only image). Pixels are in
    the frame's own pixel grid, origin top-left; ``answer_xy`` is the ground truth's exact pixel
    (``u * W, v * H``, as the official scorer compares it). ``speaker_offset`` is where the
    speaker stood (the observer camera's position, which the ground truth's directions start
    from) in metres to the frame camera's right and along its heading
    (:meth:`~povagent.geometry.camera.Camera.floor_offset`); ``facing_deg`` is the speaker's
    heading towards the anchor against the camera's heading, positive to the camera's right.
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
    speaker_offset: tuple[float, float]
    facing_deg: float
    #: Other frames that saw the anchor with its centre in view, at most :data:`OTHER_VIEWS`,
    #: widest baseline first (a second view fixes the anchor's depth, their boxes its extent).
    anchor_other_views: tuple[AnchorView, ...] = ()

    def answer_pixel(self) -> tuple[int, int]:
        """The answer in whole pixels, inside ``[0, W-1] x [0, H-1]``."""
        w, h = self.frame_size
        x, y = self.answer_xy
        return (min(max(int(round(x)), 0), w - 1), min(max(int(round(y)), 0), h - 1))


def gt_pixel(camera: Camera, target: tuple[float, float, float]) -> tuple[float, float] | None:
    """A point's pixel in ``camera`` (the ground truth's, an anchor centre's) when it lies in
    front of the camera and inside the image."""
    u, v, depth = camera.project_point(target)
    if not depth > BEHIND_EPSILON or not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
        return None
    return (u * camera.width, v * camera.height)


def teaching_frame(instance: Instance) -> Frame:
    """The frame an Inferred/Stated answer names: the target inside it, the anchor seen in it.

    Among frames whose exploration record saw the anchor and where the ground truth projects
    inside the image, frames where the anchor's centre is inside the image too come first (an
    anchor coordinate off the image teaches nothing a model can point at), then frames that also
    saw the observer's furniture, then the one whose ground truth lies nearest the image centre
    (ties: the lower index). Raises :class:`NoTeachingFrame` when no frame qualifies.
    """
    anchor_id = instance.anchor_object.objectId
    observer_id = instance.observer_object.objectId
    anchor_centre = instance.anchor_object.raw_metadata.axisAlignedBoundingBox.center.as_tuple()
    best: tuple[int, int, float, int] | None = None
    for frame in instance.frames:
        if anchor_id not in frame.in_frame_hits:
            continue
        pixel = gt_pixel(frame.camera, instance.target)
        if pixel is None:
            continue
        w, h = frame.camera.width, frame.camera.height
        off_centre = math.hypot(pixel[0] / w - 0.5, pixel[1] / h - 0.5)
        anchor_off = 0 if gt_pixel(frame.camera, anchor_centre) is not None else 1
        key = (anchor_off, 0 if observer_id in frame.in_frame_hits else 1, off_centre, frame.index)
        if best is None or key < best:
            best = key
    if best is None:
        raise NoTeachingFrame(f"{instance.id}: no frame shows the anchor with the target inside it")
    return instance.frames[best[3]]


def facing_angle(camera: Camera, observer_xz: np.ndarray, anchor_xz: np.ndarray) -> float:
    """The heading of an observer at ``observer_xz`` facing ``anchor_xz`` against ``camera``'s
    heading on the floor, in degrees in ``(-180, 180]``: 0 looks the way the camera looks,
    positive turns to the camera's right."""
    o_right, o_ahead = camera.floor_offset((observer_xz[0], 0.0, observer_xz[1]))
    a_right, a_ahead = camera.floor_offset((anchor_xz[0], 0.0, anchor_xz[1]))
    return math.degrees(math.atan2(a_right - o_right, a_ahead - o_ahead))


def facing_words(angle: float) -> str:
    """:data:`FACINGS` for a :func:`facing_angle`: within 45 degrees "away", beyond 135 "towards"."""
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


def pixel_box(camera: Camera, obj: SceneObject) -> PixelBox | None:
    """The object's box as ``camera`` sees it (:func:`~povagent.geometry.box_outline.outline`
    of its AABB: clipped to the image, the part in front when it reaches behind), to the
    nearest pixel; ``None`` when none of it shows."""
    corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float)
    box = outline(camera, corners.min(axis=0), corners.max(axis=0))
    if box is None:
        return None
    x0, y0, x1, y1 = (int(round(v)) for v in box)
    return PixelBox(x0, y0, x1, y1)


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
    if instance.povbench_condition.uses_exploration_frames:
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
    anchor_centre = (box.center.x, box.center.y, box.center.z)
    anchor_xy = _pixel(camera, anchor_centre) or (w / 2.0, h / 2.0)
    observer_pos = instance.observer_object.position.as_tuple()
    observer_xy = _pixel(camera, observer_pos)
    observer_cam = np.asarray(instance.observer_camera.position, dtype=float)
    anchor_pos = np.asarray(instance.anchor_object.position.as_tuple(), dtype=float)
    facing = facing_angle(camera, observer_cam[[0, 2]], anchor_pos[[0, 2]])
    # which way the direction points in this image: step from the target's resting point
    if spec_of(instance.povbench_direction).vertical:
        step = np.array([0.0, DIRECTION_PROBE_M, 0.0])
    else:
        step = DIRECTION_PROBE_M * direction_vectors(anchor_pos, observer_cam)[instance.povbench_direction.value]
    start = np.array([box.center.x, instance.target[1], box.center.z])
    p0, p1 = camera.project_pixels(np.stack([start, start + step]))
    if np.isfinite(p0).all() and np.isfinite(p1).all():
        towards = image_direction(float(p1[0] - p0[0]), float(p1[1] - p0[1]))
    else:
        towards = "out of view"
    other_views: tuple[AnchorView, ...] = ()
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
        other_views = tuple(
            AnchorView(i, p, pixel_box(instance.frames[i].camera, instance.anchor_object))
            for _, i, p in sorted(candidates)[:OTHER_VIEWS]
        )
    observer_visible = instance.observer_object.objectId in frame.in_frame_hits if frame_index is not None else bool(
        observer_xy and 0 <= observer_xy[0] <= w and 0 <= observer_xy[1] <= h
    )
    anchor_visible = instance.anchor_object.objectId in frame.in_frame_hits if frame_index is not None else True
    return InstanceFacts(
        instance_id=instance.id,
        condition=instance.povbench_condition.value,
        direction=instance.povbench_direction,
        frame_index=frame_index,
        frame_path=frame.image_path,
        frame_size=(w, h),
        observer_type=instance.observer_object.object_type,
        anchor_type=instance.anchor_object.object_type,
        observer_visible=observer_visible,
        anchor_visible=anchor_visible,
        anchor_xy=anchor_xy,
        anchor_box=pixel_box(camera, instance.anchor_object),
        observer_xy=observer_xy,
        observer_column=_column(observer_xy[0], w) if observer_xy is not None else None,
        facing=facing_words(facing),
        speaker_offset=camera.floor_offset(observer_cam),
        facing_deg=facing,
        relation=RELATION_WORDS[instance.povbench_direction],
        image_direction=towards,
        surface=surface_phrase(pair, instance.povbench_direction),
        answer_xy=answer,
        anchor_other_views=other_views,
    )

"""The official metric: clamped normalized L2 between the predicted pixel and the projected GT.

A/B answers are scored in the frame the model selected (its exploration camera), C answers in
the observer camera. A GT point behind the camera (depth <= 1e-6) is placed at the image centre
(0.5, 0.5) and counted out of frame: this reproduces the official scorer exactly, blind spot
included (see :func:`strict_l2` for the variant that closes it).

Coordinates are read as the official scorer reads them: an infinite one is clamped to the image
edge like any other out-of-frame value; a NaN one is kept, and its error is NaN (the official
mean then is NaN too). ``None`` is no answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from povagent.answers.spec import AnsweredCamera
from povagent.dataset.instances import Frame, Instance
from povagent.geometry.camera import BEHIND_EPSILON, Camera

#: The largest clamped error: the diagonal of the unit square.
MAX_L2 = math.sqrt(2.0)


@dataclass(frozen=True)
class GroundTruthInFrame:
    """The GT as the official scorer sees it in one camera."""

    u: float
    v: float
    in_frame: bool
    behind: bool


def project_ground_truth(target: tuple[float, float, float] | np.ndarray, camera: Camera) -> GroundTruthInFrame:
    """Project the 3D GT into a camera; behind the camera -> (0.5, 0.5), out of frame."""
    u, v, depth = camera.project_point(target)
    if not depth > BEHIND_EPSILON:
        return GroundTruthInFrame(0.5, 0.5, False, True)
    return GroundTruthInFrame(u, v, 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0, False)


def official_uv(point: tuple[float, float, float] | np.ndarray, frame: Frame) -> tuple[float, float]:
    """A 3D point where the official metric puts the GT in ``frame``: projected, clamped to
    [0, 1], and a point behind the camera at the image centre (the diagnostics' counterfactual
    targets and the probes' object centres are placed so)."""
    gt = project_ground_truth(point, frame.camera)
    return (clamp_unit(gt.u), clamp_unit(gt.v))


def clamp_unit(v: float) -> float:
    """Clamp to [0, 1] as the official scorer does (numpy's clip): NaN stays NaN."""
    # min/max alone would silently turn NaN into 0
    return v if v != v else min(1.0, max(0.0, v))


def normalized_l2(x: float, y: float, width: float, height: float, gt_u: float, gt_v: float) -> float:
    """sqrt((x/W - gu)^2 + (y/H - gv)^2) with both points clamped to [0, 1]."""
    px, py = clamp_unit(x / width), clamp_unit(y / height)
    gx, gy = clamp_unit(gt_u), clamp_unit(gt_v)
    return math.hypot(px - gx, py - gy)


def points_l2(points: list[tuple[float, float]], width: float, height: float, gt_u: float, gt_v: float) -> tuple[float, float]:
    """``(centroid error, closest point's error)`` of a multi-point answer, as officially.

    Every point and the GT are clamped to [0, 1] first; the centroid is taken of the clamped
    points (so a point far off the image weighs no more than one on its edge).
    """
    gx, gy = clamp_unit(gt_u), clamp_unit(gt_v)
    norm = [(clamp_unit(float(a) / width), clamp_unit(float(b) / height)) for a, b in points]
    cu = sum(u for u, _ in norm) / len(norm)
    cv = sum(v for _, v in norm) / len(norm)
    return math.hypot(cu - gx, cv - gy), min(math.hypot(u - gx, v - gy) for u, v in norm)


def signed_errors(x: float, y: float, width: float, height: float, gt_u: float, gt_v: float) -> tuple[float, float]:
    """``(error_x, error_y)`` as the official scorer records them: the clamped normalized
    prediction minus the clamped GT."""
    return clamp_unit(x / width) - clamp_unit(gt_u), clamp_unit(y / height) - clamp_unit(gt_v)


def point_errors(x: float, y: float, width: float, height: float, gt_u: float, gt_v: float) -> tuple[float, float, float]:
    """``(normalized_l2, error_x, error_y)`` of one point, each clamp taken once (scoring
    computes all three for every row): the same numbers as :func:`normalized_l2` and
    :func:`signed_errors`."""
    ex = clamp_unit(x / width) - clamp_unit(gt_u)
    ey = clamp_unit(y / height) - clamp_unit(gt_v)
    return math.hypot(ex, ey), ex, ey


def strict_l2(x: float, y: float, width: int, height: int, gt: GroundTruthInFrame) -> float:
    """The strict variant: a GT behind the camera or outside the frame counts as a miss (sqrt 2)."""
    if not gt.in_frame:
        return MAX_L2
    return normalized_l2(x, y, width, height, gt.u, gt.v)


@dataclass(frozen=True)
class OfficialScore:
    """The official score of one row; ``l2`` is ``None`` for a non-response."""

    answered: bool
    l2: float | None
    l2_strict: float | None
    gt_in_frame: bool | None
    gt_behind: bool | None
    gt_u: float | None
    gt_v: float | None
    reason: str = ""
    #: The signed errors ``clamp(x/W) - clamp(gt_u)`` and ``clamp(y/H) - clamp(gt_v)`` of the
    #: recorded point (a point list's first point, as the official runner recorded it): what
    #: the official ``mean_abs_x``/``mean_abs_y`` average.
    error_x: float | None = None
    error_y: float | None = None

    @property
    def l2_center(self) -> float | None:
        """The official error of guessing the centre ``(W/2, H/2)`` of the frame this row was
        scored in: the bar the answer must clear in that frame (``gt_u``/``gt_v`` are already
        normalized, so the centre is ``(0.5, 0.5)`` whatever the frame's size). A GT behind
        the camera sits at the centre, so the guess is perfect there, as officially.
        ``None`` for a non-response."""
        if not self.answered or self.gt_u is None or self.gt_v is None:
            return None
        return math.hypot(0.5 - clamp_unit(self.gt_u), 0.5 - clamp_unit(self.gt_v))

    def as_dict(self) -> dict[str, object]:
        """JSON-able form, as stored in a row's ``scores``."""
        return {
            "answered": self.answered,
            "l2": self.l2,
            "l2_strict": self.l2_strict,
            "gt_in_frame": self.gt_in_frame,
            "gt_behind": self.gt_behind,
            "gt_u": self.gt_u,
            "gt_v": self.gt_v,
            "reason": self.reason,
            "error_x": self.error_x,
            "error_y": self.error_y,
            "l2_center": self.l2_center,
        }


UNANSWERED = OfficialScore(False, None, None, None, None, None, None, "no answer")


def answered_in_camera(camera: AnsweredCamera) -> Frame:
    """The image an answer named by its camera (an active-mode view), as a frame to score in."""
    cam = Camera((camera.x, camera.y, camera.z), camera.yaw, camera.horizon, camera.fov, camera.width, camera.height)
    return Frame(index=-1, image_path="", file=Path(), camera=cam)


def scoring_frame(instance: Instance, selected_image: int | None = None, image_path: str | None = None) -> Frame | None:
    """The frame an answer is scored in: C -> the observer view; A/B -> the selected frame.

    The selected frame is named by index or by ``image_path``; an unknown or missing one gives
    ``None`` (the row is then unanswered, as officially).
    """
    if not instance.povbench_condition.uses_exploration_frames:
        return instance.frames[0]
    if image_path is not None:
        return instance.frame_by_path(image_path)
    return instance.selected_frame(selected_image)


def score_point(
    instance: Instance, frame: Frame | None, x: float | None, y: float | None, recorded: tuple[float, float] | None = None
) -> OfficialScore:
    """Score one predicted pixel ``(x, y)`` in ``frame`` against the instance's GT.

    ``None`` is unanswered; an infinite coordinate is clamped to the edge and a NaN one gives a
    NaN error, as officially. ``recorded`` is the point the official runner would have written
    as ``predicted_x``/``predicted_y`` when it is not ``(x, y)`` (a point list's first point):
    the signed errors are that point's.
    """
    if x is None or y is None:
        return UNANSWERED
    if frame is None:
        return OfficialScore(False, None, None, None, None, None, None, "missing or unknown selected frame")
    cam = frame.camera
    gt = project_ground_truth(instance.target, cam)
    l2 = normalized_l2(x, y, cam.width, cam.height, gt.u, gt.v)
    ex, ey = signed_errors(*(recorded or (x, y)), cam.width, cam.height, gt.u, gt.v)
    return OfficialScore(True, l2, strict_l2(x, y, cam.width, cam.height, gt), gt.in_frame, gt.behind, gt.u, gt.v, "", ex, ey)


def closest_point_l2(instance: Instance, frame: Frame, points: list[tuple[float, float]]) -> float | None:
    """For multi-point answers: the error of the point closest to the GT (kept beside the centroid's)."""
    if not points:
        return None
    cam = frame.camera
    gt = project_ground_truth(instance.target, cam)
    return points_l2(points, cam.width, cam.height, gt.u, gt.v)[1]

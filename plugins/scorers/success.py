"""The ``success`` scorer: a hit or a miss against hand-marked ground truth, as the paper scores real houses.

For instances of a real-world set (:mod:`povagent.dataset.realworld_set`). The answer (a pixel in the
512x512 letterboxed frame the model saw) is mapped back to the original frame through the exact
letterbox transform, then compared with the marks made in the frame the model selected (A/B) or
in the observer view (C):

* a ``point`` mark is hit within a radius: the mark's own ``radius_px``, else the scorer's
  ``radius_px`` option, else ``radius`` (default 0.1) times the original frame's diagonal.
  The diagonal-relative default makes "close enough" the same for every resolution: 0.1 of the
  diagonal is 147 px on a 1280x720 frame, and equals a normalized L2 of about 0.14 in the
  paper's metric (where the diagonal is sqrt 2).
* a ``box`` or ``region`` (polygon, even-odd rule, edges included) is hit when the point is
  inside it.

A row without a usable answer (unparseable, or no frame selected in A/B) is a failure, as the
paper counts it. Scores: ``answered``, ``success``, ``frame_has_gt`` (the selected frame carries
a mark), ``pixel`` (in the original frame), ``distance_px`` and ``distance_norm`` (to the nearest
point mark, in pixels and in diagonals; ``None`` without point marks), and ``hit_radius_px``
(the radius, in original pixels, of a point mark without its own ``radius_px`` in the scored
frame: what a report draws around such a mark).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.dataset.realworld_set import Mark, RealWorldInstance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric

#: The default hit radius, as a fraction of the original frame's diagonal.
DEFAULT_RADIUS = 0.1


def inside_polygon(x: float, y: float, polygon: Sequence[Sequence[float]]) -> bool:
    """Even-odd point-in-polygon test; points on an edge count as inside."""
    n = len(polygon)
    inside = False
    for i in range(n):
        x1, y1 = polygon[i]
        x2, y2 = polygon[(i + 1) % n]
        # on the edge: collinear and within the segment's box
        cross = (x2 - x1) * (y - y1) - (y2 - y1) * (x - x1)
        if abs(cross) <= 1e-9 * max(1.0, abs(x2 - x1) + abs(y2 - y1)) and min(x1, x2) - 1e-9 <= x <= max(x1, x2) + 1e-9 \
                and min(y1, y2) - 1e-9 <= y <= max(y1, y2) + 1e-9:
            return True
        if (y1 > y) != (y2 > y):
            x_cross = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            if x < x_cross:
                inside = not inside
    return inside


class SuccessScorer(Scorer):
    """Hit or miss against a real-world set's marks (options: ``radius``, ``radius_px``)."""

    metrics = (
        Metric(
            "success_rate",
            "higher",
            "rate",
            "success",
            "Success rate",
            "Hits / all instances, an unanswered instance counting as a failure (the paper's protocol for real houses).",
            over="all",
        ),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "Answered / total instances.", over="all"),
    )
    protocol = "marked_hit"

    def __init__(self, radius: float = DEFAULT_RADIUS, radius_px: float | None = None) -> None:
        if not isinstance(radius, (int, float)) or isinstance(radius, bool) or radius <= 0:
            raise ValueError(f"scorer option radius must be a positive fraction of the frame diagonal, got {radius!r}")
        if radius_px is not None and (not isinstance(radius_px, (int, float)) or isinstance(radius_px, bool) or radius_px <= 0):
            raise ValueError(f"scorer option radius_px must be a positive number of pixels, got {radius_px!r}")
        self.radius = float(radius)
        self.radius_px = None if radius_px is None else float(radius_px)

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """Hit or miss for one answer (see the module docstring for the fields)."""
        if not isinstance(instance, RealWorldInstance):
            raise ValueError(
                f"the success scorer needs a real-world set's instances (hand-marked GT); {instance.id} is a "
                "release-layout instance: score it with 'official'"
            )
        failure = {"answered": False, "success": False, "frame_has_gt": None, "pixel": None,
                   "distance_px": None, "distance_norm": None, "hit_radius_px": None}
        point = answer.point
        if point is None:
            return failure
        if instance.povbench_condition.uses_exploration_frames:
            k = answer.selected_image
            if k is None or instance.selected_frame(k) is None:
                return failure  # no frame: unanswered, as the official rules count it
        else:
            k = 0
        box = instance.letterboxes[k]
        px, py = (float(v) for v in box.to_original((float(point[0]), float(point[1]))))
        width, height = box.original
        diagonal = math.hypot(width, height)
        marks = instance.marks_in(instance.frames[k].image_path)
        hit = False
        nearest: float | None = None
        for mark in marks:
            hit_here, distance = self._judge(mark, px, py, diagonal)
            hit = hit or hit_here
            if distance is not None and (nearest is None or distance < nearest):
                nearest = distance
        return {
            "answered": True,
            "success": hit,
            "frame_has_gt": bool(marks),
            "pixel": [px, py],
            "distance_px": nearest,
            "distance_norm": None if nearest is None else nearest / diagonal,
            "hit_radius_px": self._radius(None, diagonal),
        }

    def _radius(self, mark: Mark | None, diagonal: float) -> float:
        """The hit radius of a point mark: its own, else the scorer's ``radius_px``, else
        ``radius`` times the frame diagonal."""
        return (mark.radius_px if mark is not None else None) or self.radius_px or self.radius * diagonal

    def _judge(self, mark: Mark, x: float, y: float, diagonal: float) -> tuple[bool, float | None]:
        if mark.point is not None:
            distance = math.hypot(x - mark.point[0], y - mark.point[1])
            return distance <= self._radius(mark, diagonal), distance
        if mark.box is not None:
            x0, y0, x1, y1 = mark.box
            return (x0 <= x <= x1 and y0 <= y <= y1), None
        return inside_polygon(x, y, mark.region or []), None


@hookimpl
def register_scorers(register) -> None:
    """Contribute the success scorer."""
    register("success", SuccessScorer, description="Real-world sets: hit within a radius or inside a marked region (unanswered = failure)")

"""The ``official`` scorer: POVBench's clamped normalized L2, blind spot included.

Beside the official ``l2`` it records the strict variant (``l2_strict``: a GT behind or outside
the scored frame counts as sqrt 2), whether the GT is in the scored frame, and for multi-point
answers the closest point's error (``l2_closest``); the centroid's error is the one reported.
It also records the error a guess at the centre of the scored frame would have had
(``l2_center``), declared as the ``center_l2`` metric: the centre baseline in the frame the
answer chose (the report's centre baseline guesses the first frame's centre instead).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent.scoring.normalized_l2 import UNANSWERED, OfficialScore, answered_in_camera, closest_point_l2, score_point, scoring_frame

#: The official number, its response rate, and the protocol's extras.
OFFICIAL_METRICS = (
    Metric("mean_l2", "lower", "mean", "l2", "Mean L2", "Official: mean clamped normalized L2 over answered instances."),
    Metric(
        "response_rate",
        "higher",
        "rate",
        "answered",
        "Response rate",
        "Answered / total instances (unparseable answers and API failures are non-responses).",
        over="all",
    ),
    Metric("strict_l2", "lower", "mean", "l2_strict", "Strict L2", "A GT behind the scored frame's camera or outside the frame counts as a miss (sqrt 2)."),
    Metric(
        "frame_accuracy",
        "higher",
        "rate",
        "gt_in_frame",
        "GT in selected frame",
        "Share of answered instances whose GT projects inside the scored frame (Inferred/Stated: frame selection).",
    ),
    Metric(
        "blind_spot",
        "lower",
        "rate",
        "gt_behind",
        "GT behind camera",
        "Share of answered instances scored by the blind spot (GT behind the camera, placed at the centre).",
    ),
    Metric(
        "center_l2",
        "lower",
        "mean",
        "l2_center",
        "Centre guess L2",
        "Mean official L2 of guessing the centre of each answered instance's scored frame: the bar its answers must clear.",
    ),
)


class OfficialScorer(Scorer):
    """Clamped normalized L2 in the selected frame (A/B), the observer view (C), or the camera
    an answer carries (the active mode's rendered views)."""

    metrics = OFFICIAL_METRICS
    protocol = "normalized_l2"
    needs_3d_target = True

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        if instance.condition is None:  # an external multiple-choice item: no point to score
            raise ValueError(
                f"instance {instance.id} is a multiple-choice item with no POVBench condition: the official scorer scores points; score it with a choice scorer"
            )
        if not answer.answered:
            return self.point_fields(UNANSWERED)
        # an answer given in a camera of its own (an active-mode view) is scored in that camera
        frame = answered_in_camera(answer.camera) if answer.camera is not None else scoring_frame(instance, answer.selected_image)
        first = answer.points[0] if answer.points else None
        closest = None
        if answer.points and len(answer.points) > 1 and frame is not None:
            closest = closest_point_l2(instance, frame, answer.points)
        return self.point_fields(score_point(instance, frame, answer.x, answer.y, first), closest)

    def point_fields(self, point: OfficialScore, l2_closest: float | None = None) -> dict[str, Any]:
        """The row fields of one placed point: the one place they are listed. A run, ``rescore``
        and ``povagent score`` (prediction files hold no parsed answer) all ask it, so a field
        added here, with its metric in :data:`OFFICIAL_METRICS`, reaches every command."""
        fields = point.as_dict()
        if l2_closest is not None:
            fields["l2_closest"] = l2_closest
        return fields


@hookimpl
def register_scorers(register) -> None:
    """Contribute the official scorer."""
    register("official", OfficialScorer, description="POVBench normalized L2 (official), with strict variant")

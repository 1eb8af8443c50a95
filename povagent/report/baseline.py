"""The center baseline, computed by the report for the instances a sweep evaluated.

The paper does not report it, yet a constant guess at the image centre is the bar every model
must clear, so every report shows it. Policy ("center, first frame"): answer the pixel
``(W/2, H/2)``; for A/B select frame 0 (the first exploration frame), for C the observer view.
It is scored with the official metric (:func:`povagent.scoring.normalized_l2.score_point`), blind
spot included, exactly like a model's answer.

The same per-instance score fills a non-response in the "counting non-responses" variant: an
unanswered instance counts as if the model had guessed the centre.

On a real-world set (hand-marked 2D ground truth, no 3D target) the same guess is judged by the
runs' ``marked_hit`` scorer instead (:func:`center_success_observations`): the official metric
would place the missing target at the image centre and call the centre guess perfect.

This module computes scores only; it does not read run folders or write anything.
"""

from __future__ import annotations

from typing import Any, Iterable

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.instances import Instance
from povagent.report.collect import Observation
from povagent.scoring.normalized_l2 import OfficialScore, score_point

#: The label of the computed baseline in tables and plots.
CENTER_SYSTEM = "Center baseline (computed)"

#: Documented policy, shown in the report's notes.
CENTER_POLICY = (
    "answers the image centre (W/2, H/2); for Inferred/Stated it selects the first exploration "
    "frame (index 0), for Given the observer view; scored with the official metric"
)


def center_score(instance: Instance) -> OfficialScore:
    """The official score of the center guess on one instance (frame 0 for A/B)."""
    frame = instance.frames[0] if instance.frames else None
    w, h = instance.frame_size
    return score_point(instance, frame, w / 2.0, h / 2.0)


def _center_guess(inst: Instance, system: str, **scores: Any) -> Observation:
    """The center guess on one instance as an observation (run 0); ``scores`` are its numbers."""
    w, h = inst.frame_size
    frame = inst.frames[0] if inst.frames else None
    return Observation(
        system=system,
        run_name="center",
        run=0,
        instance_id=inst.id,
        house_id=inst.house_id,
        pair_id=inst.pair_id,
        direction=str(inst.direction),
        condition=str(inst.condition),
        status="answered",
        parse_status="ok",
        selected_image=0 if inst.povbench_condition.uses_exploration_frames else None,
        image_path=frame.image_path if frame is not None else None,
        x=w / 2.0,
        y=h / 2.0,
        sentence=inst.sentence,
        raw=None,
        **scores,
    )


def center_observations(instances: Iterable[Instance], scorer: str, system: str = CENTER_SYSTEM) -> list[Observation]:
    """The center baseline as observations (run 0), ready to sit beside the models' rows, as
    if ``scorer`` (the runs' ``normalized_l2`` scorer) had scored them."""
    out: list[Observation] = []
    for inst in instances:
        s = center_score(inst)
        out.append(
            _center_guess(
                inst, system, answered=s.answered, l2=s.l2, l2_strict=s.l2_strict, gt_in_frame=s.gt_in_frame,
                gt_behind=s.gt_behind, gt_u=s.gt_u, gt_v=s.gt_v, scorer=scorer, protocol="normalized_l2",
            )
        )
    return out


#: The policy on a real-world set, shown in the report's notes.
CENTER_SUCCESS_POLICY = (
    "answers the image centre (W/2, H/2) of the letterboxed frame; for Inferred/Stated it selects "
    "the first exploration frame (index 0), for Given the observer view; judged by the runs' "
    "success scorer"
)


def center_success_observations(instances: Iterable[Instance], scorer: Any, name: str, system: str = CENTER_SYSTEM) -> list[Observation]:
    """The center baseline on a real-world set: the same guess, hit or miss by ``scorer`` (the
    runs' ``marked_hit`` scorer, named ``name``, built with the runs' options), as observations (run 0)."""
    out: list[Observation] = []
    for inst in instances:
        w, h = inst.frame_size
        k = 0 if inst.povbench_condition.uses_exploration_frames else None
        s = scorer.score(inst, ParsedAnswer(status=ParseStatus.OK, selected_image=k, x=w / 2.0, y=h / 2.0))
        out.append(
            _center_guess(
                inst, system, answered=bool(s["answered"]), l2=None, l2_strict=None, gt_in_frame=s["frame_has_gt"],
                gt_behind=None, gt_u=None, gt_v=None, scorer=name, protocol="marked_hit", success=bool(s["success"]),
                distance_norm=s.get("distance_norm"), hit_radius_px=s.get("hit_radius_px"),
            )
        )
    return out


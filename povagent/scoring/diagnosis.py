"""Why an answer failed: the first failing reasoning step, and the relation-consistent hit.

An addition to the official metric (never instead of it), for the ``diagnose`` and ``relation``
scorers. One answer is walked through the steps the task needs, in order, and stops at the first
that fails:

1. **frame** (A/B only): the selected frame does not show the anchor, by the release's
   occlusion-aware record of the objects each frame shows (the exploration log's
   ``object_in_frame_hits``, matched by the anchor's ``objectId``). The target stands beside the
   anchor, so a frame without the anchor cannot show where it is. (The issue words it as "shows
   neither the anchor nor the observer, or shows the anchor only"; read literally, a frame
   showing the anchor but not the observer fails, and on generated sets most instances have no
   frame showing both, so a perfect answer would fail this step. ``frame_shows`` keeps the four
   cases, ``both``, ``anchor``, ``observer``, ``neither``, so a report can use the stricter
   reading.) In C the observer view always faces the anchor: the step passes.
2. **anchor**: the point (clamped to the image, as officially) is farther than
   :data:`ANCHOR_THRESHOLD` (normalized units, the official metric's) from the anchor's
   box in the image (the part in front of the camera): the model did not find the anchor. Why 0.15: see ``docs/how-to/why-models-fail.md``
   (on generated sets every ground truth lies within it; most random answers do not).
3. **viewpoint**: the point is nearer (official clamped distance) the egocentric or the
   mirrored target (:mod:`povagent.geometry.counterfactual`) than the ground truth, counting
   only a counterfactual farther than :data:`BIAS_MARGIN` from the ground truth in this frame.
   In C the egocentric target is the ground truth itself: only the mirrored one counts.
4. **placement**: right side, wrong distance: the point is outside the relation region
   (:mod:`povagent.geometry.relation_region`);
5. **correct** otherwise.

Every counterfactual is projected as the official metric projects the ground truth
(:func:`~povagent.scoring.normalized_l2.project_ground_truth`): clamped to [0, 1], and a point behind
the camera placed at the image centre.

The egocentric-bias vote of an A/B answer: among answers that pass the frame and anchor steps
and whose egocentric and ground-truth targets lie more than :data:`BIAS_MARGIN` apart in the
answered frame (``bias_eligible``), whether the point is nearer the egocentric one
(``nearer_egocentric``). An answer in the wrong frame or far from the anchor is a guess about
neither viewpoint, and would pull the index towards one half. In C the observer view
*is* the camera, the two targets coincide, and no vote is cast (the index is left out for C).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from povagent.dataset.instances import Frame, Instance
from povagent.geometry.counterfactual import anchor_centre as counterfactual_anchor_centre
from povagent.geometry.counterfactual import egocentric_target, mirrored_target
from povagent.geometry.ground_truth import PlacementCase
from povagent.geometry.relation_region import RelationRegion, region_in_frame
from povagent.scoring.normalized_l2 import clamp_unit, official_uv
from povagent.scoring.perception import ObjectExtent, object_extent

#: Normalized distance beyond which a point is "far from the anchor" (see the module docstring).
ANCHOR_THRESHOLD = 0.15
#: Two targets closer than this (normalized) in a frame are one target: no bias vote, no viewpoint test.
BIAS_MARGIN = 0.05

#: The failure steps, in the order they are tested, then success.
STEPS: tuple[str, ...] = ("frame", "anchor", "viewpoint", "placement", "correct")


@dataclass(frozen=True)
class Diagnosis:
    """One answer's diagnosis (see the module docstring for each field's rule)."""

    step: str
    frame_shows: str
    anchor_distance: float
    l2_truth: float
    l2_egocentric: float
    l2_mirrored: float
    egocentric: tuple[float, float]
    mirrored: tuple[float, float]
    anchor_centre: tuple[float, float]
    bias_eligible: bool
    nearer_egocentric: bool | None
    relation: bool

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form, as stored in a row's ``scores["diagnose"]``."""
        return {
            "answered": True,
            "step": self.step,
            "frame_shows": self.frame_shows,
            "anchor_distance": self.anchor_distance,
            "l2_truth": self.l2_truth,
            "l2_egocentric": self.l2_egocentric,
            "l2_mirrored": self.l2_mirrored,
            "egocentric": list(self.egocentric),
            "mirrored": list(self.mirrored),
            "anchor_centre": list(self.anchor_centre),
            "bias_eligible": self.bias_eligible,
            "nearer_egocentric": self.nearer_egocentric,
            "relation": self.relation,
        }


def frame_shows(instance: Instance, frame: Frame) -> str:
    """``both``, ``anchor``, ``observer`` or ``neither`` by the frame's recorded hits; the
    observer view (C) is ``observer view``."""
    if not instance.povbench_condition.uses_exploration_frames:
        return "observer view"
    hits = frame.in_frame_hits
    anchor = str(instance.anchor_object.objectId) in hits
    observer = str(instance.observer_object.objectId) in hits
    return {(True, True): "both", (True, False): "anchor", (False, True): "observer"}.get((anchor, observer), "neither")


def anchor_extent(instance: Instance, frame: Frame) -> ObjectExtent:
    """Where the anchor of ``instance`` is in ``frame``, as the anchor step measures from it
    (:func:`~povagent.scoring.perception.object_extent`)."""
    return object_extent(instance.anchor_object, frame)


def relation_region(placements: np.ndarray, frame: Frame) -> RelationRegion:
    """The relation region of an instance's valid placements in ``frame``."""
    return region_in_frame(placements, frame.camera)


@dataclass(frozen=True)
class TargetView:
    """One target (the placement record of a (pair, direction)) seen in one frame: everything
    the diagnosis of an answer in that frame reads that does not depend on the answer. Every
    answer in that frame shares it (the Inferred and Stated instances of a target show the same
    frames, and every run of an instance), so it is worked out once per (target, camera).

    ``truth``, ``egocentric``, ``mirrored`` and ``anchor_centre`` are the targets as the official
    metric places them in the frame (:func:`official_uv`); ``anchor`` is where the anchor step
    measures from; ``region`` is the relation region."""

    truth: tuple[float, float]
    egocentric: tuple[float, float]
    mirrored: tuple[float, float]
    anchor_centre: tuple[float, float]
    anchor: ObjectExtent
    region: RelationRegion


def target_view(instance: Instance, case: PlacementCase, frame: Frame, region: RelationRegion, anchor: ObjectExtent | None = None) -> TargetView:
    """The :class:`TargetView` of ``instance``'s target in ``frame``; ``region`` is the case's
    relation region in it (:func:`relation_region`), ``anchor`` its :func:`anchor_extent` when
    already known."""
    return TargetView(
        truth=official_uv(np.asarray(instance.target, dtype=float), frame),
        egocentric=official_uv(egocentric_target(case, frame.camera), frame),
        mirrored=official_uv(mirrored_target(case), frame),
        anchor_centre=official_uv(counterfactual_anchor_centre(case), frame),
        anchor=anchor if anchor is not None else anchor_extent(instance, frame),
        region=region,
    )


def diagnose_answer(instance: Instance, view: TargetView, frame: Frame, x: float, y: float) -> Diagnosis:
    """The diagnosis of the pixel ``(x, y)`` answered in ``frame`` (see the module docstring);
    ``view`` is the target seen in that frame (:func:`target_view`)."""
    cam = frame.camera
    u, v = clamp_unit(x / cam.width), clamp_unit(y / cam.height)
    truth, ego, mirror = view.truth, view.egocentric, view.mirrored
    l2_truth = math.hypot(u - truth[0], v - truth[1])
    l2_ego = math.hypot(u - ego[0], v - ego[1])
    l2_mirror = math.hypot(u - mirror[0], v - mirror[1])
    given = not instance.povbench_condition.uses_exploration_frames
    ego_apart = not given and math.hypot(ego[0] - truth[0], ego[1] - truth[1]) > BIAS_MARGIN
    mirror_apart = math.hypot(mirror[0] - truth[0], mirror[1] - truth[1]) > BIAS_MARGIN
    shows = frame_shows(instance, frame)
    distance = view.anchor.distance(u, v)
    inside = view.region.contains(x, y)
    if shows in ("observer", "neither"):
        step = "frame"
    elif distance > ANCHOR_THRESHOLD:
        step = "anchor"
    elif (ego_apart and l2_ego < l2_truth) or (mirror_apart and l2_mirror < l2_truth):
        step = "viewpoint"
    elif not inside:
        step = "placement"
    else:
        step = "correct"
    # the vote is about the viewpoint: only answers that found the frame and the anchor cast one
    votes = ego_apart and step not in ("frame", "anchor")
    return Diagnosis(
        step=step,
        frame_shows=shows,
        anchor_distance=distance,
        l2_truth=l2_truth,
        l2_egocentric=l2_ego,
        l2_mirrored=l2_mirror,
        egocentric=ego,
        mirrored=mirror,
        anchor_centre=view.anchor_centre,
        bias_eligible=votes,
        nearer_egocentric=(l2_ego < l2_truth) if votes else None,
        relation=inside,
    )


def instance_case(instance: Instance, dataset: Any) -> PlacementCase:
    """The placement record of ``instance`` from a release-layout ``dataset`` (its houses'
    pairs); a :class:`ValueError` naming the instance when the set holds none (a real-world
    set, or no dataset given)."""
    from povagent.dataset.loader import placement_case

    houses = getattr(dataset, "houses", None)
    house = houses.get(instance.house_id) if isinstance(houses, Mapping) else None
    pair = getattr(house, "pairs", {}).get(instance.pair_id) if house is not None else None
    if pair is None:
        raise ValueError(
            f"{instance.id}: diagnostics need the release's placement records (anchor box, stage-3 verdict and surface), "
            "and the dataset given holds none for this instance (a real-world set, or no dataset)"
        )
    return placement_case(pair, instance.povbench_direction)

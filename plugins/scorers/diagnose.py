"""The ``diagnose`` scorer: the first failing reasoning step of each answer (an addition).

Per answered row, ``scores["diagnose"]`` holds ``step`` (``frame``, ``anchor``, ``viewpoint``,
``placement`` or ``correct``), ``frame_shows``, the distances to the ground truth and to the
egocentric and mirrored targets, the counterfactual targets' image positions (for drawing), and
the egocentric-bias vote (``bias_eligible``, ``nearer_egocentric``); rules and thresholds are in
:mod:`povagent.scoring.diagnosis` and ``docs/how-to/why-models-fail.md``. ``summary.json`` gathers them per
condition under ``diagnostics``. It needs a release-layout set (3D records); it never changes the
official score. Runs offline on a finished run: ``povagent rescore RUN --scorer diagnose``.
"""

from __future__ import annotations

import threading
import weakref
from typing import Any

import numpy as np

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Frame, Instance
from povagent.geometry.ground_truth import PlacementCase
from povagent.geometry.relation_region import RelationRegion, valid_placements
from povagent.interfaces import Scorer
from povagent.scoring.diagnosis import TargetView, anchor_extent, diagnose_answer, instance_case, relation_region, target_view
from povagent.scoring.normalized_l2 import scoring_frame

#: Per loaded dataset, by ``id`` (a dataset is not hashable; its entry goes when it does): the
#: geometry of its targets, shared by the ``diagnose`` and ``relation`` scorers (see
#: :class:`TargetRecords`).
_SHARED: dict[int, dict[tuple[Any, ...], Any]] = {}
_LOCK = threading.Lock()


def _shared_entry(dataset: Any) -> dict[tuple[Any, ...], Any]:
    with _LOCK:
        cache = _SHARED.get(id(dataset))
        if cache is None:
            cache = {}
            try:
                weakref.finalize(dataset, _SHARED.pop, id(dataset), None)
            except TypeError:  # no dataset, or one that cannot be weakly referenced: no shared cache
                return cache
            _SHARED[id(dataset)] = cache
        return cache


class TargetRecords:
    """The geometry of a dataset's targets, each piece worked out once per dataset and shared by
    the ``diagnose`` and ``relation`` scorers.

    A target is a (house, pair, direction): its Inferred, Stated and Given instances share one
    placement record and its valid placements; what a frame shows of it (its
    :class:`~povagent.scoring.diagnosis.TargetView`: the targets' image positions, the anchor's
    box, the relation region) depends only on the camera, and the Inferred and Stated instances
    (and every run of each) answer in the same exploration frames. The anchor's box in a frame
    is shared by the pair's four directions.
    """

    def get(self, instance: Instance, dataset: Any) -> tuple[PlacementCase, np.ndarray]:
        """``(case, valid placements)`` of ``instance``'s target."""
        cache = _shared_entry(dataset)
        key = ("case", instance.house_id, instance.pair_id, str(instance.direction))
        found = cache.get(key)
        if found is None:
            case = instance_case(instance, dataset)
            found = cache[key] = (case, valid_placements(case))
        return found

    def region(self, instance: Instance, frame: Frame, dataset: Any) -> RelationRegion:
        """The relation region of ``instance``'s target in ``frame``."""
        cache = _shared_entry(dataset)
        key = ("region", instance.house_id, instance.pair_id, str(instance.direction), frame.camera)
        found = cache.get(key)
        if found is None:
            found = cache[key] = relation_region(self.get(instance, dataset)[1], frame)
        return found

    def view(self, instance: Instance, frame: Frame, dataset: Any) -> TargetView:
        """``instance``'s target seen in ``frame``."""
        cache = _shared_entry(dataset)
        key = ("view", instance.house_id, instance.pair_id, str(instance.direction), frame.camera)
        found = cache.get(key)
        if found is None:
            anchor_key = ("anchor", instance.house_id, instance.pair_id, frame.camera)
            anchor = cache.get(anchor_key)
            if anchor is None:
                anchor = cache[anchor_key] = anchor_extent(instance, frame)
            case = self.get(instance, dataset)[0]
            found = cache[key] = target_view(instance, case, frame, self.region(instance, frame, dataset), anchor)
        return found


def answered_point(instance: Instance, answer: ParsedAnswer) -> tuple[Frame, float, float] | None:
    """The frame an answer is scored in and its point, or ``None`` when it has no scorable point
    (unanswered, no coordinates, or an unknown frame): such an answer is ``{"answered": False}``."""
    if not answer.answered or answer.x is None or answer.y is None:
        return None
    frame = scoring_frame(instance, answer.selected_image)
    return None if frame is None else (frame, float(answer.x), float(answer.y))


class DiagnoseScorer(Scorer):
    """First failing step (frame, anchor, viewpoint, placement) and the egocentric-bias vote."""

    needs_3d_target = True
    diagnosis = "failure_step"

    def __init__(self) -> None:
        self.records = TargetRecords()

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The diagnosis of one answer (``{"answered": False}`` without a scorable answer)."""
        point = answered_point(instance, answer)
        if point is None:
            return {"answered": False}
        frame, x, y = point
        return diagnose_answer(instance, self.records.view(instance, frame, dataset), frame, x, y).as_dict()


@hookimpl
def register_scorers(register) -> None:
    """Contribute the diagnose scorer."""
    register("diagnose", DiagnoseScorer, description="Addition: first failing step (frame/anchor/viewpoint/placement) and egocentric bias")

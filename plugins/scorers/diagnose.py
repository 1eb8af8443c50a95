"""The ``diagnose`` scorer: the first failing reasoning step of each answer (an addition).

Per answered row, ``scores["diagnose"]`` holds ``step`` (``frame``, ``anchor``, ``viewpoint``,
``placement`` or ``correct``), ``frame_shows``, the distances to the ground truth and to the
egocentric and mirrored targets, the counterfactual targets' image positions (for drawing), and
the egocentric-bias vote (``bias_eligible``, ``nearer_egocentric``); rules and thresholds are in
:mod:`povagent.scoring.diagnosis` and ``docs/diagnostics.md``. ``summary.json`` gathers them per
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
from povagent.scoring.diagnosis import diagnose_answer, instance_case, relation_region
from povagent.scoring.official import scoring_frame

#: Per loaded dataset, by ``id`` (a dataset is not hashable; its entry goes when it does): each
#: instance's record and valid placements.
_SHARED: dict[int, dict[str, tuple[PlacementCase, np.ndarray]]] = {}
_LOCK = threading.Lock()


#: Per loaded dataset: relation regions by (instance, frame), for the two scorers of one answer.
_REGIONS: dict[int, dict[tuple[str, str, int], RelationRegion]] = {}


def _cache_for(dataset: Any) -> dict[str, tuple[PlacementCase, np.ndarray]]:
    return _shared_entry(_SHARED, dataset)


def _regions_for(dataset: Any) -> dict[tuple[str, str, int], RelationRegion]:
    return _shared_entry(_REGIONS, dataset)


def _shared_entry(table: dict[int, Any], dataset: Any) -> Any:
    with _LOCK:
        cache = table.get(id(dataset))
        if cache is None:
            cache = {}
            try:
                weakref.finalize(dataset, table.pop, id(dataset), None)
            except TypeError:  # no dataset, or one that cannot be weakly referenced: no shared cache
                return cache
            table[id(dataset)] = cache
        return cache


class InstanceRecords:
    """Each instance's placement record and valid placements, computed once per dataset and
    shared by the ``diagnose`` and ``relation`` scorers."""

    def get(self, instance: Instance, dataset: Any) -> tuple[PlacementCase, np.ndarray]:
        """``(case, valid placements)`` of ``instance``."""
        cache = _cache_for(dataset)
        found = cache.get(instance.id)
        if found is None:
            case = instance_case(instance, dataset)
            found = cache[instance.id] = (case, valid_placements(case))
        return found

    def region(self, instance: Instance, frame: Frame, dataset: Any) -> RelationRegion:
        """The relation region of ``instance`` in ``frame`` (made once: both scorers ask)."""
        cache = _regions_for(dataset)
        key = (instance.id, frame.image_path, frame.index)
        found = cache.get(key)
        if found is None:
            found = cache[key] = relation_region(self.get(instance, dataset)[1], frame)
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

    def __init__(self) -> None:
        self.records = InstanceRecords()

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The diagnosis of one answer (``{"answered": False}`` without a scorable answer)."""
        point = answered_point(instance, answer)
        if point is None:
            return {"answered": False}
        frame, x, y = point
        case, _ = self.records.get(instance, dataset)
        region = self.records.region(instance, frame, dataset)
        return diagnose_answer(instance, case, region, frame, x, y).as_dict()


@hookimpl
def register_scorers(register) -> None:
    """Contribute the diagnose scorer."""
    register("diagnose", DiagnoseScorer, description="Addition: first failing step (frame/anchor/viewpoint/placement) and egocentric bias")

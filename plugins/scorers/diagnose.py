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

from typing import Any

import numpy as np

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.geometry.ground_truth import PlacementCase
from povagent.geometry.relation_region import valid_placements
from povagent.interfaces import Scorer
from povagent.scoring.diagnosis import diagnose_answer, instance_case
from povagent.scoring.official import scoring_frame


class InstanceRecords:
    """Each instance's placement record and valid placements, computed once per scorer."""

    def __init__(self) -> None:
        self._cache: dict[tuple[int, str], tuple[PlacementCase, np.ndarray]] = {}

    def get(self, instance: Instance, dataset: Any) -> tuple[PlacementCase, np.ndarray]:
        """``(case, valid placements)`` of ``instance``."""
        key = (id(dataset), instance.id)
        found = self._cache.get(key)
        if found is None:
            case = instance_case(instance, dataset)
            found = self._cache[key] = (case, valid_placements(case))
        return found


class DiagnoseScorer(Scorer):
    """First failing step (frame, anchor, viewpoint, placement) and the egocentric-bias vote."""

    def __init__(self) -> None:
        self.records = InstanceRecords()

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The diagnosis of one answer (``{"answered": False}`` without a scorable answer)."""
        if not answer.answered or answer.x is None or answer.y is None:
            return {"answered": False}
        frame = scoring_frame(instance, answer.selected_image)
        if frame is None:
            return {"answered": False}
        case, placements = self.records.get(instance, dataset)
        return diagnose_answer(instance, case, placements, frame, float(answer.x), float(answer.y)).as_dict()


@hookimpl
def register_scorers(register) -> None:
    """Contribute the diagnose scorer."""
    register("diagnose", DiagnoseScorer, description="Addition: first failing step (frame/anchor/viewpoint/placement) and egocentric bias")

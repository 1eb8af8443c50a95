"""The ``relation`` scorer: a hit when the point lands where a valid target could stand (an addition).

The point counts as correct when it lies in the image region covered by a 0.4 m target placed
anywhere that still satisfies the sentence's relation from the observer's viewpoint, on the same
supporting surface ("up": on the anchor's top), in the frame the answer was scored in
(:mod:`povagent.geometry.relation_region` has the sampling rules and the tolerance). The official
L2 stays the paper's number; ``summary.json``'s ``diagnostics`` puts the success rate beside it
per direction. Scores: ``answered``, ``success``, ``margin_px`` (how far outside the region the
point is, negative inside; ``None`` when no valid placement is in front of the camera),
``region_empty``.
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent_plugins.scorers.diagnose import TargetRecords, answered_point


class RelationScorer(Scorer):
    """Success when the point lies in the relation region of the answered frame."""

    needs_3d_target = True
    diagnosis = "relation_hit"

    def __init__(self) -> None:
        self.records = TargetRecords()

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """Hit or miss of one answer (``{"answered": False}`` without a scorable answer)."""
        point = answered_point(instance, answer)
        if point is None:
            return {"answered": False}
        frame, x, y = point
        region = self.records.region(instance, frame, dataset)
        margin = region.margin(x, y)
        return {"answered": True, "success": margin is not None and margin <= 0.0, "margin_px": margin, "region_empty": region.empty}


@hookimpl
def register_scorers(register) -> None:
    """Contribute the relation scorer."""
    register("relation", RelationScorer, description="Addition: hit when the point lands where a valid 0.4 m target could stand")

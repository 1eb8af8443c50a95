"""The ``anchor-check`` scorer: where the answered point lies relative to the anchor object
(the ``anchor-point`` type's gold), in the image the answer names."""

from __future__ import annotations

import math
from typing import Any

from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent.scoring.normalized_l2 import project_ground_truth, scoring_frame
from povagent_anchor_kit.answer import ANCHOR_POINT


class AnchorCheckScorer(Scorer):
    """Two numbers: whether the anchor is in the answered image at all, and how far the point
    lies from it there (normalized image coordinates)."""

    metrics = (
        Metric("anchor_in_view", "higher", "rate", "anchor_in_view", "Anchor in view",
               "Share of instances whose answered image shows the anchor (no answer: no).", over="all"),
        Metric("anchor_offset", "lower", "mean", "anchor_offset", "Anchor offset",
               "Mean normalized distance from the point to the anchor, where the anchor is in view."),
    )  # fmt: skip

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        value = ANCHOR_POINT.value_of(answer)
        frame = scoring_frame(instance, value["selected_image"]) if value is not None else None
        if value is None or frame is None:
            return {"answered": False}
        anchor = project_ground_truth(ANCHOR_POINT.gold(instance), frame.camera)
        width, height = frame.camera.width, frame.camera.height
        offset = math.hypot(value["x"] / width - anchor.u, value["y"] / height - anchor.v) if anchor.in_frame else None
        return {"answered": True, "anchor_in_view": anchor.in_frame, "anchor_offset": offset}

"""A scorer plugin: success when the official normalized L2 is within a radius.

The official metric puts the predicted pixel and the ground truth in [0, 1] x [0, 1] of the
scored frame (the selected frame for A/B, the observer view for C) and measures their distance;
this scorer calls an answer a success when that distance is at most ``radius`` (an option,
default 0.1). In a pipeline YAML::

    plugins: [within_radius_scorer.py]
    scorers: [official, {name: within-radius, options: {radius: 0.05}}]

Each row then carries ``scores["within-radius"]``: ``success``, ``l2`` and ``radius``.
"""

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.normalized_l2 import score_point, scoring_frame


class WithinRadiusScorer(Scorer):
    """Success within ``radius`` of the ground truth, in the official normalized L2."""

    def __init__(self, radius: float = 0.1) -> None:
        if isinstance(radius, bool) or not isinstance(radius, (int, float)) or radius <= 0:
            raise ValueError(f"radius must be a positive number (a normalized L2), got {radius!r}")
        self.radius = float(radius)

    def score(self, instance: Instance, answer: ParsedAnswer, dataset) -> dict:
        """``success``, the official ``l2`` it rests on, and the ``radius`` used."""
        official = score_point(instance, scoring_frame(instance, answer.selected_image), answer.x, answer.y)
        # No frame (an index the model was never shown) is no answer: a failure, as officially.
        success = official.l2 is not None and official.l2 <= self.radius
        return {"success": success, "l2": official.l2, "radius": self.radius}


@hookimpl
def register_scorers(register):
    """Contribute the within-radius scorer."""
    register("within-radius", WithinRadiusScorer, description="Success when the official normalized L2 <= radius")

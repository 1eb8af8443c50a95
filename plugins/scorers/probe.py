"""The ``probe-anchor`` and ``probe-observer`` scorers: how far a pointed pixel is from the object
(an addition, for the perception probes of the same names).

Per answered row, in the frame it is scored in (the selected frame, or the observer view),
``scores["probe-anchor"]`` (or ``probe-observer``) holds the error against the object's
projected box (``box_error``, 0 inside; ``inside_box``; ``None`` when no part of it is in the
image: ``in_view`` false) and against its projected centre (``centre_error``), in the official
metric's normalized units, with ``seen`` (the frame's record lists the object; the observer
view always shows the anchor and never the observer) and ``object_type``
(:mod:`povagent.scoring.perception`). ``summary.json``'s ``scorers`` section gives their means
and rates. It needs a release-layout or generated set's objects (every POVBench-format set has
them); it never changes the official score.
"""

from __future__ import annotations

from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.perception import pointing_error
from povagent_plugins.scorers.diagnose import answered_point


class ProbeScorer(Scorer):
    """The pointing error against one object of the instance (``role``: anchor or observer)."""

    role: ClassVar[str] = "anchor"
    needs_3d_target = True

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The pointing error of one answer (``{"answered": False}`` without a scorable answer)."""
        point = answered_point(instance, answer)
        if point is None:
            return {"answered": False}
        frame, x, y = point
        obj = instance.anchor_object if self.role == "anchor" else instance.observer_object
        if instance.povbench_condition.uses_exploration_frames:
            seen = str(obj.objectId) in frame.in_frame_hits
        else:
            seen = self.role == "anchor"  # the observer view faces the anchor, from the observer
        return pointing_error(obj, frame, x, y, seen)


class AnchorProbeScorer(ProbeScorer):
    """Error against the anchor."""

    role = "anchor"


class ObserverProbeScorer(ProbeScorer):
    """Error against the observer's object."""

    role = "observer"


@hookimpl
def register_scorers(register) -> None:
    """Contribute the two probe scorers."""
    register("probe-anchor", AnchorProbeScorer, description="Addition: pointing error against the anchor's projected box and centre")
    register("probe-observer", ObserverProbeScorer, description="Addition: pointing error against the observer object's projected box and centre")

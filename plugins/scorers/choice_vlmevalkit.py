"""The ``choice-vlmevalkit`` scorer: VLMEvalKit's spatial-bench hit test, bug included, and its correction.

VLMEvalKit's ``compute_mcq_score`` (``vlmeval/dataset/utils/spatial_bench/cal_scores.py`` at the
commit the ``vlmevalkit-spatial`` parser names) reads the gold answer with the same rule as the
reply and counts a hit when the two readings are equal as lower-cased strings. Where neither
yields a letter both are ``False``, and ``"false" == "false"``: a reply naming no option scores
a hit on every question whose gold the rule cannot read (a gold ``G``, or a numbered option).
The bug is in scoring, not parsing, so it is a scorer: ``choice-vlmevalkit`` reproduces it, and
``choice-vlmevalkit-corrected`` requires a letter on both sides. Pair either with the
``vlmevalkit-spatial`` parser to score as VLMEvalKit does. Fields and metrics are the
``choice`` scorer's; ``gold_read`` is the letter the rule reads in the gold label (or ``None``).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent_plugins.parsers.mcq.vlmevalkit_spatial import spatial_bench_label
from povagent_plugins.scorers.choice_scorer import ChoiceScorer


def _as_vlmevalkit_writes(letter: str | None) -> str:
    """A reading as ``compute_mcq_score`` compares it: the letter, or ``False``, lower-cased."""
    return str(letter if letter is not None else False).strip().lower()


def same_as_vlmevalkit_compares(chosen: str | None, gold_read: str | None) -> bool:
    """``compute_mcq_score``'s hit: the two readings equal as lower-cased text, ``None`` written
    as ``False`` (so two readings of nothing are equal)."""
    return _as_vlmevalkit_writes(chosen) == _as_vlmevalkit_writes(gold_read)


class VlmevalkitChoiceScorer(ChoiceScorer):
    """Hit as ``compute_mcq_score`` counts it (module docstring)."""

    corrected = False

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The ``choice`` scorer's fields, ``correct`` as VLMEvalKit (or the correction) decides."""
        scores = super().score(instance, answer, dataset)
        gold_read = spatial_bench_label(str(scores["gold"]).strip())
        chosen = scores["chosen"]
        same = same_as_vlmevalkit_compares(chosen, gold_read)
        scores["correct"] = same and (not self.corrected or chosen is not None)
        scores["gold_read"] = gold_read
        return scores


class CorrectedVlmevalkitChoiceScorer(VlmevalkitChoiceScorer):
    """``compute_mcq_score`` with a hit requiring a letter on both sides."""

    corrected = True


@hookimpl
def register_scorers(register) -> None:
    """Contribute VLMEvalKit's hit test and its correction."""
    register(
        "choice-vlmevalkit",
        VlmevalkitChoiceScorer,
        description=("Multiple choice as VLMEvalKit's compute_mcq_score counts a hit, bug included: no letter on either side is a hit"),
    )
    register(
        "choice-vlmevalkit-corrected",
        CorrectedVlmevalkitChoiceScorer,
        description=("Multiple choice as VLMEvalKit's compute_mcq_score counts a hit, corrected: a hit needs a letter on both sides"),
    )

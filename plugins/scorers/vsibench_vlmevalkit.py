"""The ``vsibench-vlmevalkit`` scorer: VSI-Bench as VLMEvalKit's ``VsiBench.evaluate`` scores it.

At open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94 (``vlmeval/dataset/vsibench.py``,
``vlmeval/dataset/utils/spatial_bench/cal_scores.py``), with no judge:

* a multiple-choice question is a hit when the letter read in the reply equals the letter
  ``can_match_option`` reads in the gold answer, compared as lower-cased text
  (``compute_mcq_score``), as the ``choice-vlmevalkit`` scorer compares them (two readings of
  nothing would be equal, ``"false" == "false"``; VSI-Bench's golds are the letters A-D, which the
  rule always reads, so that never fires on the set);
* a numerical question scores the mean relative accuracy of the number read
  (``compute_na_score``, 0 when none is read) over the set's ten thresholds, with VLMEvalKit's
  own relative error ``abs_dist_norm``: ``|(pred - gold) / gold|``, and ``|pred - gold|`` for a
  gold of 0, where the set's code divides by the gold itself (a negative gold, an error below 0)
  and fails on a gold of 0. On VSI-Bench's golds, all above 0, the two agree;
* ``_aggregate``: the mean score of each question type, the three ``object_rel_direction_*``
  levels averaged into one **only when all three have questions** (else each counts as a type of
  its own, where the set's code raises), and the overall the mean of those type scores. Its
  table prints them times 100; here they are fractions of 1, as for the set's other rules.

The row fields are the ``vsibench`` scorer's; ``gold_read`` is the letter read in the gold.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent.scoring.relative_accuracy import absolute_error, accuracy_over_thresholds
from povagent_plugins.parsers.mcq.vlmevalkit_spatial import spatial_bench_label
from povagent_plugins.scorers.choice_vlmevalkit import same_as_vlmevalkit_compares
from povagent_plugins.scorers.vsibench_scorer import DIRECTION_LEVELS, VSIBenchScorer


def vlmevalkit_relative_error(prediction: float, gold: float) -> float:
    """VLMEvalKit's ``abs_dist_norm``: ``|prediction - gold|`` for a gold of 0, else
    ``|(prediction - gold) / gold|``."""
    return abs(prediction - gold) if gold == 0.0 else abs((prediction - gold) / gold)


def question_score(instance: Instance, answer: ParsedAnswer) -> dict[str, Any]:
    """The row's fields (module docstring) for one answered or unanswered question."""
    if instance.question is not None:
        chosen = answer.choice if answer.status.answered else None
        gold_read = spatial_bench_label(str(instance.question.gold).strip())
        correct = same_as_vlmevalkit_compares(chosen, gold_read)
        return {
            "answered": chosen is not None,
            "score": 1.0 if correct else 0.0,
            "correct": correct,
            "chosen": chosen,
            "gold": instance.question.gold,
            "gold_read": gold_read,
            "category": instance.question.category,
        }
    numeric = instance.numeric
    if numeric is None:
        raise ValueError(f"instance {instance.id} asks neither a multiple-choice nor a numerical question")
    number = answer.number if answer.status.answered else None
    fields: dict[str, Any] = {"answered": number is not None, "gold": numeric.gold, "unit": numeric.unit, "category": numeric.category}
    if number is None:
        return {**fields, "score": 0.0}
    error = vlmevalkit_relative_error(number, numeric.gold)
    mra = accuracy_over_thresholds(error)
    fields.update(score=mra, mra=mra, number=number if math.isfinite(number) else None)
    if math.isfinite(number):
        fields.update(abs_error=absolute_error(number, numeric.gold), rel_error=error)
    return fields


class VlmevalkitVSIBenchScorer(Scorer):
    """VSI-Bench scored as VLMEvalKit scores it (module docstring)."""

    metrics: ClassVar[tuple[Metric, ...]] = (
        Metric(
            "score",
            "higher",
            "mean",
            "score",
            "VSI-Bench score (VLMEvalKit)",
            "Accuracy (multiple choice) or mean relative accuracy (numbers) per question as VLMEvalKit's VsiBench scores them, "
            "a reply read as nothing scoring 0; per category the question type's score, overall the mean of the type scores, "
            "the three direction levels first averaged into one when all three have questions.",
            over="all",
            unscored=0.0,
            category_mean=True,
            merged_categories=(DIRECTION_LEVELS,),
            merge_only_whole=True,
        ),
        *VSIBenchScorer.metrics[1:3],
        Metric(
            "rel_error",
            "lower",
            "mean",
            "rel_error",
            "Relative error",
            "|(answer - gold) / gold| of the finite numerical answers read (VLMEvalKit's abs_dist_norm; |answer - gold| for a gold of 0).",
        ),
        VSIBenchScorer.metrics[4],
    )

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The question's score and what was compared."""
        return question_score(instance, answer)


@hookimpl
def register_scorers(register) -> None:
    """Contribute VSI-Bench as VLMEvalKit scores it."""
    register(
        "vsibench-vlmevalkit",
        VlmevalkitVSIBenchScorer,
        description=(
            "VSI-Bench as VLMEvalKit's VsiBench scores it: its letter match for multiple choice, mean relative accuracy with its "
            "abs_dist_norm for numbers; direction levels merged only when all three have questions"
        ),
    )

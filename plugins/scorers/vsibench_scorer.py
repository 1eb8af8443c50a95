"""The ``vsibench`` scorer and VSI-Bench's overall, as the set's own code and lmms-eval compute it.

Per question (``vsibench_process_results`` at vision-x-nyu/thinking-in-space@51e089c3, the same
in lmms-eval @ 75571cfe): a multiple-choice question scores 1 when the parsed word is the gold
letter in either case, else 0; a numerical question scores its mean relative accuracy
(:func:`povagent.scoring.relative_accuracy.mean_relative_accuracy`), 0 when the rule read no
number (``WORST_CASE_FOR_METRICS``). The row's ``score`` is that value; ``category`` is the
question type. Numerical rows also carry ``mra``, ``abs_error`` and ``rel_error``.

A numerical question whose gold is 0 and whose reply reads a number has no relative error: both
upstream codes divide by the gold there and stop (``ZeroDivisionError``; VSI-Bench's golds are all
above 0). Such a row is **unscorable**, a recorded outcome rather than a silent gap: its fields say
``unscorable: true`` and why (:data:`UNSCORABLE_REASON`), it carries no ``score``, ``mra`` nor
``rel_error`` (so the set's figures are those of the questions it can score), and the declared
``unscorable`` metric counts it (``summary.json``; ``povagent rescore-log`` names each such row).
A reply reading no number scores 0 there as anywhere (upstream reaches its worst case before it
divides).

The set's overall is not the mean over questions: it is the mean of the per-type means, with
the three ``object_rel_direction_{easy,medium,hard}`` types first averaged into one
(``vsibench_aggregate_results``): :func:`official_overall`. lmms-eval @ 75571cfe averages the
same way (``_compute_all_subscores``) but rounds to 6 places on a 0-1 scale where the set's
script prints percent, and requires all three direction levels (a run without one raises
``KeyError`` there; the set's own code merges them only when ``easy`` is present):
:func:`lmms_overall`. The declared ``score`` metric's per-category cells are the type scores and
its ``overall`` cell the set's overall (``Metric.category_mean``), so ``summary.json``, the
console and the report show it; where a direction level has no question it averages the levels
present, where both upstream functions raise.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.choice_sets.vsibench_records import CHOICE_TYPES, NUMBER_TYPES
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent.scoring.relative_accuracy import absolute_error, mean_relative_accuracy, relative_error

#: The three direction levels the overall first averages into one type.
DIRECTION_LEVELS = ("object_rel_direction_easy", "object_rel_direction_medium", "object_rel_direction_hard")
DIRECTION = "object_rel_direction"
#: Why a numerical row whose gold is 0 is not scored (module docstring).
UNSCORABLE_REASON = "the gold is 0: the relative error |answer - gold| / gold is undefined (the set's code and lmms-eval's divide by it and stop)"


def question_score(instance: Instance, answer: ParsedAnswer) -> dict[str, Any]:
    """The row's fields (module docstring) for one answered or unanswered question."""
    if instance.question is not None:
        chosen = answer.choice if answer.status.answered else None
        correct = chosen is not None and chosen.lower() == instance.question.gold.lower()
        return {
            "answered": chosen is not None,
            "score": 1.0 if correct else 0.0,
            "correct": correct,
            "chosen": chosen,
            "gold": instance.question.gold,
            "category": instance.question.category,
        }
    numeric = instance.numeric
    if numeric is None:
        raise ValueError(f"instance {instance.id} asks neither a multiple-choice nor a numerical question")
    number = answer.number if answer.status.answered else None
    fields: dict[str, Any] = {"answered": number is not None, "gold": numeric.gold, "unit": numeric.unit, "category": numeric.category}
    if number is None:
        return {**fields, "score": 0.0}
    if numeric.gold == 0.0:
        finite = math.isfinite(number)
        return {
            **fields,
            "number": number if finite else None,
            **({"abs_error": absolute_error(number, 0.0)} if finite else {}),
            "unscorable": True,
            "unscorable_reason": UNSCORABLE_REASON,
        }
    mra = mean_relative_accuracy(number, numeric.gold)
    fields.update(score=mra, mra=mra, number=number if math.isfinite(number) else None)
    if math.isfinite(number):
        fields.update(abs_error=absolute_error(number, numeric.gold), rel_error=relative_error(number, numeric.gold))
    return fields


class VSIBenchScorer(Scorer):
    """VSI-Bench's per-question score (module docstring)."""

    metrics: ClassVar[tuple[Metric, ...]] = (
        Metric(
            "score",
            "higher",
            "mean",
            "score",
            "VSI-Bench score",
            "Accuracy (multiple choice) or mean relative accuracy (numbers) per question, a reply the rule reads nothing "
            "in scoring 0; per category the question type's score, overall the set's: the mean of the type scores, "
            "the three direction levels first averaged into one.",
            over="all",
            unscored=0.0,
            category_mean=True,
            merged_categories=(DIRECTION_LEVELS,),
        ),
        Metric("mra", "higher", "mean", "mra", "MRA", "Mean relative accuracy of the numerical answers read (10 thresholds, 0.50-0.95)."),
        Metric("abs_error", "lower", "mean", "abs_error", "Absolute error", "|answer - gold| of the finite numerical answers read, in the question's unit."),
        Metric("rel_error", "lower", "mean", "rel_error", "Relative error", "|answer - gold| / gold of the finite numerical answers read."),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "Replies the rule reads an answer in / all questions.", over="all"),
        Metric(
            "unscorable",
            "lower",
            "rate",
            "unscorable",
            "Unscorable",
            "Numerical questions whose gold is 0 with a number read / all questions: no relative error exists, so score and "
            "MRA leave them out; each row says so (unscorable_reason).",
            over="all",
        ),
    )

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The question's score and what was compared."""
        return question_score(instance, answer)


def per_type_scores(scores: Iterable[tuple[str, float]]) -> dict[str, float]:
    """The mean score of each question type, from ``(question type, score)`` pairs, types in
    sorted order (pandas' ``groupby``). An unknown type is a :class:`ValueError`, as upstream."""
    sums: dict[str, list[float]] = {}
    for question_type, score in scores:
        if question_type not in CHOICE_TYPES and question_type not in NUMBER_TYPES:
            raise ValueError(f"Unknown question type: {question_type}")
        sums.setdefault(question_type, []).append(score)
    return {t: math.fsum(v) / len(v) for t, v in sorted(sums.items())}


def _merged(per_type: Mapping[str, float], reading: str) -> dict[str, float]:
    out = dict(per_type)
    missing = [level for level in DIRECTION_LEVELS if level not in out]
    if reading == "lmms" or DIRECTION_LEVELS[0] in out:
        if missing:
            raise ValueError(f"the {reading} overall averages the three direction levels, and {', '.join(missing)} has no question (upstream raises KeyError)")
        levels = [out.pop(level) for level in DIRECTION_LEVELS]
        out[DIRECTION] = sum(levels) / 3.0
    return out


def official_overall(per_type: Mapping[str, float]) -> dict[str, float]:
    """The set's own table, fractions of 1 (its script prints them times 100): every type's score
    with the direction levels averaged into ``object_rel_direction`` when ``..._easy`` has
    questions, and ``overall``, the mean of those scores."""
    out = _merged(per_type, "official")
    return {"overall": sum(out.values()) / len(out), **out}


def lmms_overall(per_type: Mapping[str, float]) -> dict[str, float]:
    """lmms-eval's table: as :func:`official_overall`, each value rounded to 6 places (its
    ``round(..., 6)``), the three direction levels required."""
    out = _merged(per_type, "lmms")
    overall = sum(out.values()) / len(out)
    return {"overall": round(overall, 6), **{k: round(v, 6) for k, v in out.items()}}


@hookimpl
def register_scorers(register) -> None:
    """Contribute the VSI-Bench scorer."""
    register(
        "vsibench",
        VSIBenchScorer,
        description=(
            "VSI-Bench: accuracy for its multiple-choice questions, mean relative accuracy for its numerical ones "
            "(0 for a reply read as nothing); the set's overall is the mean of its per-type scores"
        ),
    )

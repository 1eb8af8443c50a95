"""The ``choice-mmsi-circular`` scorer: MMSI-Bench's circular evaluation.

The circular split asks each question four times, its options rotated
(:mod:`povagent.dataset.choice_sets.mmsi_circular_copies`); copy ``k`` of question ``i`` has the id
``i + k * 1,000,000``. The set's authors (``MMSIBenchCircular.evaluate``,
InternRobotics/MMSI-Bench@5de2f3d2, ``vlmeval/dataset/mmsi_bench.py``) and VLMEvalKit
(``mcq_circular_eval`` and ``report_acc``, open-compass/VLMEvalKit@e8e78f05,
``vlmeval/dataset/utils/multiple_choice.py``) group the copies by ``id mod 1,000,000`` and count:

- ``circular_accuracy`` (the headline): questions whose every copy is right / questions; a copy
  whose reply names no option is wrong and sinks its question;
- ``vanilla_accuracy``: over each question's first copy alone (id below 1,000,000, the options in
  their own order), right / questions: the authors' "Vanilla" column beside "Circular";

each overall and per question type (a plain mean over the questions of the type). A group is the
copies present: a run has all four; a harness's file missing one is judged on the rest, as both
upstream codes judge it (VLMEvalKit leaves out a question whose first copy is missing; here it
counts, as the authors count it).

The grouping is a pattern on the copy's id (:class:`~povagent.scoring.metrics.Metric` ``group``):
the digits before the last six and the zeros that then lead are removed, which turns
``2000017`` into ``17`` as ``id mod 1,000,000`` does for every id the split makes.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.scoring.metrics import Metric
from povagent_plugins.scorers.choice_scorer import QuestionCopiesScorer

#: Removed from a copy's id to name its question: ``id mod 1,000,000`` for ids below 10**12.
QUESTION_OF_COPY = r"^(?:\d+(?=\d{6}$))?0*(?=\d)"
#: A question's first copy: an id of at most six digits.
FIRST_COPY = r"^\d{1,6}$"


class MMSICircularScorer(QuestionCopiesScorer):
    """The choice scorer's fields, the copy's question and option order, and the circular and vanilla accuracies."""

    #: the circular evaluation is the split's number
    headline = "circular_accuracy"

    metrics = (
        Metric(
            "circular_accuracy",
            "higher",
            "rate",
            "correct",
            "Circular accuracy",
            "Questions with all four rotated copies right / all questions (no option read = wrong).",
            over="all",
            group=QUESTION_OF_COPY,
        ),
        Metric(
            "vanilla_accuracy",
            "higher",
            "rate",
            "correct",
            "Vanilla accuracy",
            "Questions whose first copy (options in their own order) is right / all questions.",
            over="all",
            select=FIRST_COPY,
        ),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "Answers naming an option / all copies.", over="all"),
    )


@hookimpl
def register_scorers(register) -> None:
    """Contribute MMSI-Bench's circular scorer."""
    register(
        "choice-mmsi-circular",
        MMSICircularScorer,
        description="MMSI-Bench circular: a question right only when its four rotated copies all are; vanilla: its first copy",
    )

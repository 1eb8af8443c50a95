"""The ``choice-3dsrbench`` scorer: a choice scorer with 3DSRBench's four accuracies.

3DSRBench asks each question in copies (:mod:`povagent.dataset.choice_sets.srbench3d_records`), its
qid the instance's pair id: the question ``Q``, its flipped copy ``Q-flip`` (the answer
mirrored), its circular copies ``Q-N`` (the options rotated), and ``Q-flip-N``. Its accuracies,
as VLMEvalKit's ``_3DSRBench.evaluate`` (@ e8e78f05), the authors' circular results script and
lmms-eval's ``3dsrbench`` task (@ 75571cfe) group the copies, each a rate over groups of copies, a
group right only when every copy in it is (:class:`povagent.scoring.metrics.Metric` ``group``);
every slice has all four, overall, per sub-category and per type (a question counts in both:
:data:`povagent.dataset.choice_sets.srbench3d_records.TYPES`):

- ``vanilla_accuracy``: correct / every record (every copy counts once);
- ``flip_accuracy``: a copy and its flipped twin (the qid with ``-flip`` removed: ``Q`` with
  ``Q-flip``, ``Q-2`` with ``Q-flip-2``);
- ``circular_accuracy``: a question's circular copies, the flipped ones apart (the qid with
  its ``-N`` removed: ``Q``, ``Q-1``, ... and ``Q-flip``, ``Q-flip-1``, ...);
- ``flip_circular_accuracy``: every copy of the question (the qid up to its first ``-``).

An answer naming no option is wrong and sinks its group, as in
:mod:`povagent_plugins.scorers.choice_scorer`. Each row also records the question it is a copy of
and which copy (``question_group``, ``variant``: ``ChoiceQuestion.group`` and ``variant``).
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.scoring.metrics import Metric
from povagent_plugins.scorers.choice_scorer import QuestionCopiesScorer

#: What each grouped accuracy removes from a qid to name the copy's group.
FLIP_PAIR = r"-flip"
CIRCULAR_SET = r"-\d+$"
QUESTION = r"-.*$"


class SRBench3DScorer(QuestionCopiesScorer):
    """The choice scorer's fields, the copy's question and variant, and 3DSRBench's four accuracies."""

    #: the authors' circular evaluation is the set's number
    headline = "circular_accuracy"

    metrics = (
        Metric(
            "vanilla_accuracy",
            "higher",
            "rate",
            "correct",
            "Vanilla accuracy",
            "Correct / all records, every copy counted once (no option read = wrong).",
            over="all",
        ),
        Metric(
            "flip_accuracy",
            "higher",
            "rate",
            "correct",
            "Flip accuracy",
            "Pairs of a copy and its flipped twin with both right / all pairs.",
            over="all",
            group=FLIP_PAIR,
        ),
        Metric(
            "circular_accuracy",
            "higher",
            "rate",
            "correct",
            "Circular accuracy",
            "Sets of a question's circular copies (flipped ones apart) all right / all sets.",
            over="all",
            group=CIRCULAR_SET,
        ),
        Metric(
            "flip_circular_accuracy",
            "higher",
            "rate",
            "correct",
            "Flip+Circular accuracy",
            "Questions with every copy right / all questions.",
            over="all",
            group=QUESTION,
        ),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "Answers naming an option / all records.", over="all"),
    )


@hookimpl
def register_scorers(register) -> None:
    """Contribute the 3DSRBench scorer."""
    register("choice-3dsrbench", SRBench3DScorer, description="3DSRBench: vanilla, Flip, Circular and Flip+Circular accuracy over a question's copies")

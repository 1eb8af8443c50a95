"""The ``choice-mindcube`` scorer: a choice scorer whose overall leaves out MindCube's ``translation`` setting.

MindCube's own evaluator (``src/evaluation/evaluator.py`` and ``core/base_metrics.py`` at the
commit the ``mindcube-official`` parser names) scores each setting (``around``, ``rotation``,
``translation``, ``among``, ``other``: the reader's categories) and reports an overall accuracy
over every setting but ``translation`` (``include_in_overall: False``); the setting's own
accuracy is still reported. Here that is a setting of the scorer, ``overall_excludes`` (default
``["translation"]``; ``[]`` counts every question overall): the accuracy and response rate of
the ``overall`` slice leave those categories out, their own slices keep them. Fields are the
``choice`` scorer's.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import ClassVar

from povagent import hookimpl
from povagent.scoring.metrics import Metric
from povagent_plugins.scorers.choice_scorer import ChoiceScorer

#: The settings MindCube's evaluator leaves out of its overall accuracy.
MINDCUBE_OVERALL_EXCLUDES = ("translation",)


def _excluding(categories: tuple[str, ...]) -> tuple[Metric, ...]:
    """The choice scorer's metrics, their overall leaving ``categories`` out."""
    return tuple(dataclasses.replace(m, overall_excludes=categories) for m in ChoiceScorer.metrics)


class MindCubeChoiceScorer(ChoiceScorer):
    """The choice scorer, its overall leaving out the categories named (module docstring)."""

    metrics: ClassVar[tuple[Metric, ...]] = _excluding(MINDCUBE_OVERALL_EXCLUDES)

    def __new__(cls, overall_excludes: Sequence[str] = MINDCUBE_OVERALL_EXCLUDES) -> MindCubeChoiceScorer:
        if isinstance(overall_excludes, str) or not all(isinstance(c, str) and c for c in overall_excludes):
            raise ValueError(f"overall_excludes must be a list of category names, got {overall_excludes!r}")
        excluded = tuple(overall_excludes)
        if excluded != MINDCUBE_OVERALL_EXCLUDES:
            # metrics are what a scorer class declares: another setting is a class declaring its own
            cls = type(cls.__name__, (cls,), {"metrics": _excluding(excluded), "__module__": cls.__module__})
        return super().__new__(cls)

    def __init__(self, overall_excludes: Sequence[str] = MINDCUBE_OVERALL_EXCLUDES) -> None:
        super().__init__()


@hookimpl
def register_scorers(register) -> None:
    """Contribute the MindCube scorer."""
    register(
        "choice-mindcube",
        MindCubeChoiceScorer,
        description=(
            "Multiple choice as MindCube's evaluator reports it: the overall leaves out the translation setting "
            "(option overall_excludes), each setting's own accuracy kept"
        ),
    )

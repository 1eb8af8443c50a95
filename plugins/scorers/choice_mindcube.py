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

from povagent import hookimpl
from povagent_plugins.scorers.choice import ChoiceScorer

#: The settings MindCube's evaluator leaves out of its overall accuracy.
MINDCUBE_OVERALL_EXCLUDES = ("translation",)


class MindCubeChoiceScorer(ChoiceScorer):
    """The choice scorer, its overall leaving out the categories named (module docstring)."""

    metrics = tuple(dataclasses.replace(m, overall_excludes=MINDCUBE_OVERALL_EXCLUDES) for m in ChoiceScorer.metrics)

    def __init__(self, overall_excludes: Sequence[str] = MINDCUBE_OVERALL_EXCLUDES) -> None:
        if isinstance(overall_excludes, str) or not all(isinstance(c, str) and c for c in overall_excludes):
            raise ValueError(f"overall_excludes must be a list of category names, got {overall_excludes!r}")
        excluded = tuple(overall_excludes)
        self.metrics = tuple(dataclasses.replace(m, overall_excludes=excluded) for m in ChoiceScorer.metrics)


@hookimpl
def register_scorers(register) -> None:
    """Contribute the MindCube scorer."""
    register("choice-mindcube", MindCubeChoiceScorer, description=(
        "Multiple choice as MindCube's evaluator reports it: the overall leaves out the translation setting "
        "(option overall_excludes), each setting's own accuracy kept"))  # fmt: skip

"""The ``choice-sparbench`` scorer: lmms-eval's SPAR-Bench multiple-choice hit, bugs included.

lmms-eval's SPAR-Bench ``exact_match`` (see the ``sparbench-lmms`` parser) counts an empty reply
as a hit whatever the gold, and a reply whose first character is the gold letter. The
``sparbench-lmms`` parser gives that first character as the label and marks an empty reply;
this scorer then counts a hit where the label equals the gold (case aside, as lmms-eval
lower-cases both) or the reply was empty. For the corrected reading, parse with
``sparbench-lmms-corrected`` and score with ``choice``. Fields and metrics are the ``choice``
scorer's.
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent_plugins.parsers.mcq.sparbench import EMPTY_REPLY
from povagent_plugins.scorers.choice_scorer import ChoiceScorer


class SparBenchChoiceScorer(ChoiceScorer):
    """Hit as SPAR-Bench's ``exact_match`` counts it (module docstring)."""

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The ``choice`` scorer's fields, ``correct`` as lmms-eval's SPAR-Bench decides."""
        scores = super().score(instance, answer, dataset)
        chosen = scores["chosen"]
        same = chosen is not None and chosen.lower() == str(scores["gold"]).lower()
        scores["correct"] = same or answer.reason == EMPTY_REPLY
        return scores


@hookimpl
def register_scorers(register) -> None:
    """Contribute SPAR-Bench's hit test."""
    register(
        "choice-sparbench",
        SparBenchChoiceScorer,
        description=("Multiple choice as lmms-eval's SPAR-Bench exact_match counts a hit, bugs included: an empty reply is a hit (parse with sparbench-lmms)"),
    )

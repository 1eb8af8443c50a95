"""The sets a report's runs were asked, when they name more than one (ViewSpatial-Bench runs
beside MindCube runs, a point task beside a relation task on one house set).

Each run keeps its own set (:meth:`RunSets.for_run`), so a question is looked up in the set its
run asked; :meth:`RunSets.instance` answers a caller that knows no run with the first set
holding the id. This module opens nothing (:func:`~povagent.report.analysis.load_collection_dataset`
does) and computes no number.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence


@dataclass
class RunSets:
    """Several opened sets, in the order the runs first name them, and each run's."""

    sets: Sequence[Any]
    by_run: Mapping[str, Any] = field(default_factory=dict)

    @property
    def root(self) -> Path:
        """The first set's folder (where a card's image names are read from)."""
        return Path(self.sets[0].root)

    @property
    def problems(self) -> list[Any]:
        """Every set's problems, in order."""
        return [p for s in self.sets for p in getattr(s, "problems", [])]

    def for_run(self, run_name: str) -> Any:
        """The set the run named ``run_name`` asked (the first set for a run it does not know)."""
        return self.by_run.get(run_name, self.sets[0])

    def instance(self, id_: str) -> Any:
        """The instance ``id_`` of the first set holding it (``None``: none does)."""
        for s in self.sets:
            found = s.instance(id_)
            if found is not None:
                return found
        return None

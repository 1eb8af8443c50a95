"""The sets a report's runs were asked, opened as the runner opened them
(:func:`load_collection_dataset`), and, when the runs name more than one (ViewSpatial-Bench runs
beside MindCube runs, a point task beside a relation task on one house set), all of them.

Each run keeps its own set (:meth:`RunSets.for_run`), so a question is looked up in the set its
run asked; :meth:`RunSets.instance` answers a caller that knows no run with the first set
holding the id. This module computes no number.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from povagent.report.collect import Collection, RunInfo


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


def load_collection_dataset(collection: Collection | list[RunInfo], override: str | Path | None = None, sets: Any = None):
    """The set the runs were asked (``override`` in place of its file or folder), or
    ``(None, reason)`` if it cannot load (``collection``: a collection, or the runs
    :func:`~povagent.report.collect.find_runs` found, so that a report loads the set before it
    holds the rows' observations).

    Each set is opened as the runner opened it: a release-layout set, a real-world set
    (``realworld.json``, whose letterboxed frames the gallery draws on), or an external
    multiple-choice set's file in its ``dataset.format`` (with its ``dataset.images``), asked
    as the run's ``task:``. Runs asking different sets get them all
    (:class:`~povagent.report.run_sets.RunSets`, each run's own). ``sets``: the report's
    :class:`~povagent.report.choice_gold.SetQuestions`, so each set is opened once per report.
    """
    from povagent.report.choice_gold import SetQuestions, run_set_key

    sets = SetQuestions() if sets is None else sets

    runs = collection.runs if isinstance(collection, Collection) else collection
    keys = {r.name: run_set_key(r, Path(override) if override else None) for r in runs}
    distinct = list(dict.fromkeys(k for k in keys.values() if k is not None))
    if not distinct:
        if override:  # no config names a set: the folder given, read as a release or real-world set
            distinct = [(Path(override), None, None, None, None)]
        else:
            return None, "no dataset path in the runs' config.yaml (pass --dataset)"
    # No load-time image check: the gallery draws a card for every row and says on it
    # which image failed, instead of the house vanishing from the report.
    opened = {key: sets.opened(key) for key in distinct}
    failed = [reason for reason in opened.values() if isinstance(reason, str)]
    if failed:
        return None, f"dataset not loadable: {failed[0]}"
    if len(opened) == 1:
        return next(iter(opened.values())), None
    return RunSets([opened[k] for k in distinct], {name: opened[k] for name, k in keys.items() if k is not None}), None

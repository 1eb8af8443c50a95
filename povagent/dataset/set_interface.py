"""What the runner needs of an evaluation set, whichever kind it is.

The release-layout :class:`~povagent.dataset.loader.Dataset` and the hand-marked
:class:`~povagent.dataset.realworld_set.RealWorldDataset` both satisfy :class:`EvaluationSet`, so the
runner, sweeps and reports treat them alike and never probe for attributes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable, Mapping, Protocol, Sequence, runtime_checkable

from povagent.dataset.instances import Instance
from povagent.dataset.problems import Problem
from povagent.dataset.release_models import Condition, Direction


@runtime_checkable
class EvaluationSet(Protocol):
    """A loaded set of instances: houses, the problems met loading them, and the rules it
    imposes on scorers."""

    root: Path
    problems: list[Problem]

    @property
    def houses(self) -> Mapping[str, Any]:
        """The loaded houses by id (read only: a set's own type may be more precise)."""

    def instances(
        self,
        conditions: Iterable[Condition | str] | None = None,
        directions: Iterable[Direction | str] | None = None,
        houses: Iterable[str] | None = None,
    ) -> Sequence[Instance]:
        """The instances selected, grouped by house (a house's frames are read together)."""
        ...

    def instance(self, id_: str) -> Instance | None:
        """The instance with id ``house/pair/direction/condition``, or ``None``."""
        ...

    def check_scorers(self, scorers: Mapping[str, Any]) -> None:
        """Raise :class:`~povagent.errors.ConfigError` when a scorer (``{name: scorer}``, objects
        or factories) cannot score this set (before any request is made); return quietly otherwise."""
        ...

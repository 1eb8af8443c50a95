"""The rows of a breakdown table, labelled: overall, each condition, each direction (and each
question category, for a breakdown that has them: a multiple-choice run's declared metrics).

Every console table of a breakdown (the official means, success rates, declared metrics, the
official reading beside a lenient one) lists its slices in this order with these labels; a
module of its own so the tables' modules need not import each other.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Protocol, TypeVar

C = TypeVar("C", covariant=True)


class Slices(Protocol[C]):
    """A breakdown of any cell type: official means (:class:`~povagent.run.summary_model.Cell`)
    or success rates (:class:`~povagent.run.summary_model.SuccessCell`)."""

    @property
    def overall(self) -> C: ...

    @property
    def per_condition(self) -> Mapping[str, C]: ...

    @property
    def per_direction(self) -> Mapping[str, C]: ...


def breakdown_slices(breakdown: Slices[C]) -> Iterator[tuple[str, C]]:
    """The rows of a breakdown table, labelled: overall, each condition, each direction."""
    from povagent.dataset.release_models import Condition

    yield "overall", breakdown.overall
    known = {str(c) for c in Condition}
    for c, cell in breakdown.per_condition.items():
        # a type the official rows wrote oddly (e.g. "A") is its own group: shown as written
        yield (f"{Condition(c).label} ({c.upper()})" if c in known else f"type {c!r}"), cell
    yield from breakdown.per_direction.items()
    # a multiple-choice set's items have no condition or direction: their category instead; a
    # category that is a direction with the same numbers (povagent's relation task) is listed once
    for category, cell in (getattr(breakdown, "per_category", None) or {}).items():
        if breakdown.per_direction.get(category) != cell:
            yield f"category {category!r}", cell

"""What model calls cost, summed: the one aggregator of tokens, cost and retries.

A row sums its exchanges, a summary sums its rows, the agent sums its turns: each through
:meth:`UsageTotals.of`. A provider may not state tokens or cost, so each field is summed over
the items that state it; what an all-silent sum is (``None``, or ``0`` where a count is
expected) is the caller's word, given as ``unstated_tokens`` / ``unstated_cost``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Iterable, Protocol, cast


class Spent(Protocol):
    """Anything that states tokens and cost: a response's usage, an exchange record, a row."""

    @property
    def prompt_tokens(self) -> int | None: ...

    @property
    def completion_tokens(self) -> int | None: ...

    @property
    def cost_usd(self) -> float | None: ...


def _stated_tokens(values: Iterable[int | None]) -> int | None:
    """The sum of the counts that are stated; ``None`` when none is."""
    return _stated_sum(values)


def _stated_cost(values: Iterable[float | None]) -> float | None:
    """The sum of the costs that are stated (in their order); ``None`` when none is."""
    return _stated_sum(values)


def _stated_sum(values: Iterable[Any]) -> Any:
    # summed as they come (as sum() of the stated ones would, from 0): nothing held a value
    total: Any = 0
    stated = False
    for v in values:
        if v is not None:
            total += v
            stated = True
    return total if stated else None


@dataclass(frozen=True)
class UsageTotals:
    """Tokens and cost summed over some items; retries summed when the items carry them."""

    prompt_tokens: int | None
    completion_tokens: int | None
    cost_usd: float | None
    retries: int = 0

    @classmethod
    def of(
        cls, items: Iterable[Spent], *, unstated_tokens: int | None = None, unstated_cost: float | None = None
    ) -> UsageTotals:
        """The totals of ``items``; a field no item states is ``unstated_tokens`` (token counts)
        or ``unstated_cost`` (cost)."""
        return cls(*usage_sums(items, unstated_tokens=unstated_tokens, unstated_cost=unstated_cost))

    @classmethod
    def summed(
        cls,
        prompt_tokens: Iterable[int | None],
        completion_tokens: Iterable[int | None],
        cost_usd: Iterable[float | None],
        retries: Iterable[int | None],
        *,
        unstated_tokens: int | None = None,
        unstated_cost: float | None = None,
    ) -> UsageTotals:
        """:meth:`of` items given field by field (each field's values in the items' order): the
        same sums, without an object an item (a summary holds its rows' usage in columns)."""
        prompt, completion, cost = _stated_tokens(prompt_tokens), _stated_tokens(completion_tokens), _stated_cost(cost_usd)
        return cls(
            prompt_tokens=unstated_tokens if prompt is None else prompt,
            completion_tokens=unstated_tokens if completion is None else completion,
            cost_usd=unstated_cost if cost is None else cost,
            retries=_retries_sum(retries),
        )

    def plus(self, item: Spent) -> UsageTotals:
        """``UsageTotals.of((self, item), unstated_tokens=0, unstated_cost=0.0)``: the same sums in
        the same order, without building a sequence (a run adds each row it writes)."""
        return UsageTotals(
            prompt_tokens=_stated_pair(self.prompt_tokens, item.prompt_tokens, 0),
            completion_tokens=_stated_pair(self.completion_tokens, item.completion_tokens, 0),
            cost_usd=_stated_pair(self.cost_usd, item.cost_usd, 0.0),
            retries=0 + int(self.retries or 0) + int(getattr(item, "retries", 0) or 0),
        )


def usage_sums(
    items: Iterable[Spent], *, unstated_tokens: int | None = None, unstated_cost: float | None = None
) -> tuple[int | None, int | None, float | None, int]:
    """:meth:`UsageTotals.of`'s ``(prompt_tokens, completion_tokens, cost_usd, retries)``, as a
    tuple: a caller that only copies the sums (a run's row, every key) makes no object for them."""
    items = items if type(items) is list or isinstance(items, Sequence) else list(items)  # a sequence's items may be built when read
    if len(items) == 1:  # a row of one exchange (every single-turn key): the same sums, from 0, in one pass
        (item,) = items
        prompt, completion, cost = item.prompt_tokens, item.completion_tokens, item.cost_usd
        return (
            unstated_tokens if prompt is None else 0 + prompt,
            unstated_tokens if completion is None else 0 + completion,
            unstated_cost if cost is None else 0 + cost,
            0 + int(getattr(item, "retries", 0) or 0),
        )
    totals = UsageTotals.summed(
        (i.prompt_tokens for i in items),
        (i.completion_tokens for i in items),
        (i.cost_usd for i in items),
        (getattr(i, "retries", 0) for i in items),
        unstated_tokens=unstated_tokens,
        unstated_cost=unstated_cost,
    )
    return totals.prompt_tokens, totals.completion_tokens, totals.cost_usd, totals.retries


def _retries_sum(retries: Iterable[int | None]) -> int:
    """``sum(int(r or 0) for r in retries)``; summed at C speed when every value is an int (a
    summary's column of its rows' retries)."""
    values = list(retries)
    if set(map(type, values)) <= {int}:
        return sum(cast("list[int]", values))
    return sum(int(r or 0) for r in values)


class RunningTotals:
    """:class:`UsageTotals` summed in place, an item at a time, from stated zeros: after
    ``add(i)`` for each item, :meth:`totals` is ``UsageTotals(0, 0, 0.0).plus(i1).plus(i2)...``
    to the bit, without a frozen object made an item (a run adds every row it writes)."""

    __slots__ = ("prompt_tokens", "completion_tokens", "cost_usd", "retries")

    def __init__(self) -> None:
        self.prompt_tokens: int = 0
        self.completion_tokens: int = 0
        self.cost_usd: float = 0.0
        self.retries: int = 0

    def add(self, item: Spent) -> None:
        """One more item's tokens, cost and retries (an unstated one adds nothing)."""
        # a stated total plus an unstated value is the total, as plus() keeps it
        if (prompt := item.prompt_tokens) is not None:
            self.prompt_tokens += prompt
        if (completion := item.completion_tokens) is not None:
            self.completion_tokens += completion
        if (cost := item.cost_usd) is not None:
            self.cost_usd += cost
        self.retries += int(getattr(item, "retries", 0) or 0)

    def totals(self) -> UsageTotals:
        """The sums so far."""
        return UsageTotals(self.prompt_tokens, self.completion_tokens, self.cost_usd, self.retries)


def _stated_pair(a: Any, b: Any, unstated: Any) -> Any:
    """:func:`_stated_sum` of ``(a, b)``, or ``unstated`` when neither is stated."""
    total: Any = 0
    stated = False
    if a is not None:
        total += a
        stated = True
    if b is not None:
        total += b
        stated = True
    return total if stated else unstated

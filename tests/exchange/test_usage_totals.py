"""The one aggregator of tokens, cost and retries (rows, summaries and the agent use it)."""

from __future__ import annotations

from povagent.exchange.messages import Usage
from povagent.exchange.usage_totals import UsageTotals


def test_each_field_sums_the_items_that_state_it():
    spent = UsageTotals.of([Usage(10, 2, 0.5), Usage(None, 3, None), Usage(5, None, 0.25)])
    assert spent == UsageTotals(prompt_tokens=15, completion_tokens=5, cost_usd=0.75, retries=0)


def test_a_field_no_item_states_is_the_callers_unstated_value():
    silent = [Usage(), Usage()]
    assert UsageTotals.of(silent) == UsageTotals(None, None, None, 0)
    assert UsageTotals.of(silent, unstated_tokens=0, unstated_cost=0.0) == UsageTotals(0, 0, 0.0, 0)


def test_retries_are_summed_from_items_that_carry_them():
    class Exchange:
        prompt_tokens, completion_tokens, cost_usd = 1, 1, None

        def __init__(self, retries: int) -> None:
            self.retries = retries

    assert UsageTotals.of([Exchange(2), Exchange(3)]).retries == 5


def test_one_item_sums_as_several_do_from_zero():
    class Exchange:
        def __init__(self, prompt, completion, cost, retries) -> None:
            self.prompt_tokens, self.completion_tokens, self.cost_usd, self.retries = prompt, completion, cost, retries

    zero = Exchange(0, 0, 0.0, 0)
    for item in (Exchange(7, None, -0.0, 2), Exchange(None, 3, 1e-05, None), Exchange(True, 2, 0.25, 1)):
        alone, with_zero = UsageTotals.of([item], unstated_tokens=0), UsageTotals.of([zero, item], unstated_tokens=0)
        assert alone == with_zero and [type(v) for v in vars(alone).values()] == [type(v) for v in vars(with_zero).values()]
        assert str(alone.cost_usd) == str(with_zero.cost_usd)  # -0.0 summed from 0 is 0.0, as several items give it


def test_items_given_field_by_field_sum_as_the_items_do():
    items = [Usage(10, None, 0.1), Usage(None, None, None), Usage(5, 2, 0.2), Usage(True, 3, -0.0)]
    columns = [[getattr(u, f) for u in items] for f in ("prompt_tokens", "completion_tokens", "cost_usd")]
    for unstated in ({}, {"unstated_tokens": 0, "unstated_cost": 0.0}):
        summed = UsageTotals.summed(*columns, [0, None, 2, 1], **unstated)
        of = UsageTotals.of(items, **unstated)
        assert (summed.prompt_tokens, summed.completion_tokens, summed.cost_usd) == (of.prompt_tokens, of.completion_tokens, of.cost_usd)
        assert summed.retries == 3 and str(summed.cost_usd) == str(of.cost_usd)
    silent = UsageTotals.summed([None], [None], [None], [None])
    assert silent == UsageTotals(None, None, None, 0) == UsageTotals.of([Usage()])


def test_running_totals_are_the_totals_plus_gives_item_by_item():
    from povagent.exchange.usage_totals import RunningTotals

    class Row:
        def __init__(self, prompt, completion, cost, retries) -> None:
            self.prompt_tokens, self.completion_tokens, self.cost_usd, self.retries = prompt, completion, cost, retries

    rows = [Row(7, None, -0.0, 2), Row(None, 3, 1e-05, None), Row(True, 2, 0.1, 1), Row(None, None, None, 0), Row(5, 1, 0.2, 3)]
    running, chained = RunningTotals(), UsageTotals(0, 0, 0.0)
    assert running.totals() == chained
    for row in rows:
        running.add(row)
        chained = chained.plus(row)
        assert running.totals() == chained and repr(running.totals()) == repr(chained)  # the same sums, types and signs

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

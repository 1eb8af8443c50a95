"""Interventions on Given run, but stay out of the paper-layout tables by default
(povagent/report/paper_protocol.py and ``collect``): the authors ran them on Inferred and Stated only."""

from __future__ import annotations

import pytest

from povagent.report.collect import collect
from povagent.report.paper_protocol import outside_paper_protocol, paper_conditions


@pytest.mark.parametrize("strategy", ["o-plot", "oa-plot", "cot", "spatial-cot"])
def test_the_interventions_are_in_the_protocol_on_inferred_and_stated_only(strategy):
    assert paper_conditions(strategy) == {"a", "b"}
    assert outside_paper_protocol(strategy, "c") and not outside_paper_protocol(strategy, "a")


def test_the_basic_strategy_and_unknown_strategies_cover_every_condition():
    assert not outside_paper_protocol("basic", "c")
    assert not outside_paper_protocol("someone-elses-strategy", "c")


def test_given_rows_of_an_intervention_are_left_out_of_the_report_by_default(mini_dataset, make_sweep):
    folder = make_sweep([{"model": "mock-a", "strategy": "cot"}], name="cot")
    default = collect(folder)
    n_given = len(mini_dataset.instances(conditions=["c"]))
    assert {o.condition for o in default.observations} == {"a", "b"}
    assert default.outside_protocol_rows == n_given
    kept = collect(folder, outside_protocol=True)
    assert {o.condition for o in kept.observations} == {"a", "b", "c"} and kept.outside_protocol_rows == 0


def test_given_rows_of_the_basic_strategy_stay(make_sweep):
    collection = collect(make_sweep([{"model": "mock-a", "strategy": "basic"}], name="basic"))
    assert {o.condition for o in collection.observations} == {"a", "b", "c"} and collection.outside_protocol_rows == 0


def test_a_baseline_under_an_intervention_keeps_its_given_rows(make_sweep):
    """A baseline never reads the prompt: its rows are the same under any strategy."""
    collection = collect(make_sweep([{"model": "center", "strategy": "cot"}], name="center"))
    assert "c" in {o.condition for o in collection.observations}

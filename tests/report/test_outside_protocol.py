"""Interventions on Given run, but stay out of the paper-layout tables by default
(povagent/report/protocol.py and ``collect``): the authors ran them on Inferred and Stated only."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.report.collect import collect
from povagent.report.protocol import outside_paper_protocol, paper_conditions
from povagent.run.runner import run_pipeline


@pytest.mark.parametrize("strategy", ["o-plot", "oa-plot", "cot", "spatial-cot"])
def test_the_interventions_are_in_the_protocol_on_inferred_and_stated_only(strategy):
    assert paper_conditions(strategy) == {"a", "b"}
    assert outside_paper_protocol(strategy, "c") and not outside_paper_protocol(strategy, "a")


def test_the_basic_strategy_and_unknown_strategies_cover_every_condition():
    assert not outside_paper_protocol("basic", "c")
    assert not outside_paper_protocol("someone-elses-strategy", "c")


def run(tmp_path, mini_root, strategy):
    path = tmp_path / f"{strategy}.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": str(mini_root),
        "backend": "center",
        "strategy": strategy,
        "instances": {"conditions": ["a", "c"], "houses": ["train_house_00000"]},
        "output": str(tmp_path / strategy),
    }))
    run_pipeline(load_pipeline(path))
    return tmp_path / strategy


def test_given_rows_of_an_intervention_are_left_out_of_the_report_by_default(tmp_path, mini_root):
    folder = run(tmp_path, mini_root, "cot")
    default = collect(folder)
    assert {o.condition for o in default.observations} == {"a"}
    assert default.outside_protocol_rows == 4  # house 0: one pair, four directions on C
    kept = collect(folder, outside_protocol=True)
    assert {o.condition for o in kept.observations} == {"a", "c"} and kept.outside_protocol_rows == 0


def test_given_rows_of_the_basic_strategy_stay(tmp_path, mini_root):
    collection = collect(run(tmp_path, mini_root, "basic"))
    assert {o.condition for o in collection.observations} == {"a", "c"} and collection.outside_protocol_rows == 0

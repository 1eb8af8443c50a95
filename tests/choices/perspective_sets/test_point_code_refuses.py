"""POVBench-only code refuses an external item (no direction, no condition) with a clear error
instead of failing somewhere inside: a choice pipeline never sends one there."""

from __future__ import annotations

import pytest

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.choice_sets import load_choice_set
from povagent.exchange.images import ImageStore
from povagent.plugins import get_plugin_host


@pytest.fixture
def item(set_file):
    return load_choice_set(set_file("viewspatial"), "viewspatial").instances()[0]


def test_a_point_strategy_refuses_an_item_without_a_condition(item):
    strategy = get_plugin_host().strategy("basic", {})
    with pytest.raises(ValueError, match="multiple-choice item with no POVBench condition: ask it with the choice strategy"):
        strategy.build(item, ImageStore())


def test_the_official_scorer_refuses_an_item_without_a_condition(item):
    scorer = get_plugin_host().scorer("official", {})
    answer = ParsedAnswer(status=ParseStatus.OK, x=1.0, y=1.0)
    with pytest.raises(ValueError, match="the official scorer scores points; score it with a choice scorer"):
        scorer.score(item, answer)


def test_an_item_without_a_condition_answers_no_frame(item):
    assert item.answers_a_frame is False

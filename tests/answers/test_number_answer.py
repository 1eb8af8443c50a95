"""The ``number`` answer type: registered by its built-in plugin module, its value is the parsed
number, its gold value the numeric question's number and unit, and a parse carrying no number
writes no ``number`` key (rows of the other types keep their bytes)."""

from __future__ import annotations

import math

import pytest

from povagent.answers.numeric_question import NumericQuestion
from povagent.answers.spec import ParsedAnswer, ParseStatus, unparseable
from povagent.plugins import build_plugin_host


def test_number_is_registered_by_its_built_in_plugin_module():
    host = build_plugin_host()
    assert host.entry("answer_type", "number").source == "built-in povagent_plugins.answers.number"


def test_a_number_value_is_the_parsed_number_and_shows_with_its_unit():
    number = build_plugin_host().answer_type("number")
    parse = ParsedAnswer(status=ParseStatus.OK, number=3.5)
    assert parse.answered
    assert number.value_of(parse) == {"number": 3.5}
    assert number.show({"number": 3.5, "unit": "meters"}) == "3.5 meters"
    assert number.value_of(unparseable("no number")) is None


def test_an_infinite_number_is_an_answer_whose_value_is_null():
    number = build_plugin_host().answer_type("number")
    parse = ParsedAnswer(status=ParseStatus.OK, number=math.inf)
    assert number.value_of(parse) == {"number": None}
    assert number.show({"number": None}) == "not a finite number"
    assert ParsedAnswer.model_validate_json(parse.model_dump_json()).number == math.inf


def test_a_parse_without_a_number_writes_no_number_key():
    assert "number" not in ParsedAnswer(status=ParseStatus.OK, choice="A").model_dump()
    assert ParsedAnswer(status=ParseStatus.OK, number=2.0).model_dump()["number"] == 2.0


def test_a_numeric_question_refuses_a_gold_that_is_no_finite_number():
    with pytest.raises(ValueError, match="finite number"):
        NumericQuestion("How many chairs?", math.nan)
    with pytest.raises(ValueError, match="finite number"):
        NumericQuestion("How many chairs?", True)  # type: ignore[arg-type]
    assert NumericQuestion("How far?", 2, unit="meters").shown(2.5) == "2.5 meters"

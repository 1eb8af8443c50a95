"""A collection's tables make equal values one object, and never change what a value prints."""

from __future__ import annotations

import math

from povagent.report.shared_values import label_table, number_table


def test_equal_floats_become_one_object():
    same = number_table()
    first = same(float("0.25"))
    assert same(float("0.25")) is first and same(0.5) is not first


def test_values_that_equal_others_yet_print_otherwise_stay_themselves():
    same = number_table()
    same(0.0), same(1.0)
    negative_zero = same(-0.0)
    assert math.copysign(1.0, negative_zero) == -1.0
    assert type(same(1)) is int and type(same(True)) is bool
    nan = float("nan")
    assert same(nan) is nan and same(None) is None


def test_equal_labels_become_one_string():
    share = label_table()
    first = share("".join(["train_house", "/0"]))
    assert share("".join(["train_house", "/0"])) is first

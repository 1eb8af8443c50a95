"""The rescale-1000 decision rule at its edges (plugins/parsers/rescale.py states the rule).

1. fractions: 0 <= x <= 1 and 0 <= y <= 1 with at least one not whole -> x*W, y*H (a value at
   the end of its range, 1.0, lands on the last pixel, W-1);
2. 0-1000 by overshoot: x > W-1+m or y > H-1+m, m = max(2, 0.02 W), both in [0, 1000];
3. otherwise left as read; negative values are never repaired. A 100-pixel frame makes the
   margin exactly 2, so the threshold 99 + 2 = 101 is exact in floating point.
"""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent_plugins.parsers.rescale import FRACTIONS, THOUSANDTHS, Rescale1000Parser, declares_1000, overshoot_margin

SMALL = AnswerSpec(schema=point_answer_schema(100, 100), width=100, height=100, asks_frame=False)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)
INFERRED = AnswerSpec(schema=frame_answer_schema(3, 512, 512), n_frames=3)


def parse(text, spec=GIVEN):
    return Rescale1000Parser().parse(text, spec)


def test_the_margin_is_two_percent_of_the_side_but_at_least_two_pixels():
    assert overshoot_margin(512) == pytest.approx(10.24)
    assert overshoot_margin(50) == 2.0


@pytest.mark.parametrize(("x", "y", "expected"), [(0.0, 0.5, (0.0, 256.0)), (0.25, 0.0, (128.0, 0.0)), (1.0, 0.25, (511.0, 128.0)), (0.5, 1.0, (256.0, 511.0))])
def test_fractions_on_the_unit_square_edges_are_rescaled(x, y, expected):
    parsed = parse(f'{{"x": {x}, "y": {y}}}')
    assert parsed.repair == FRACTIONS
    assert (parsed.x, parsed.y) == pytest.approx(expected)


@pytest.mark.parametrize(("x", "y"), [(-0.5, 0.5), (0.5, -0.5)])
def test_negative_values_are_never_repaired(x, y):
    parsed = parse(f'{{"x": {x}, "y": {y}}}')
    assert parsed.repair is None
    assert (parsed.x, parsed.y) == (x, y)


def test_an_overshoot_up_to_the_margin_is_a_pixel_answer():
    for x in (101.0, 100.0):
        parsed = parse(f'{{"x": {x}, "y": 50}}', SMALL)
        assert parsed.repair is None and parsed.x == x
    for y in (101.0,):
        assert parse(f'{{"x": 50, "y": {y}}}', SMALL).repair is None


def test_an_overshoot_past_the_margin_is_read_as_0_1000():
    parsed = parse('{"x": 101.5, "y": 50}', SMALL)
    assert parsed.repair == THOUSANDTHS
    assert (parsed.x, parsed.y) == pytest.approx((101.5 / 1000 * 100, 50 / 1000 * 100))
    assert "[0, 99] x [0, 99]" in parsed.reason
    assert parse('{"x": 50, "y": 101.5}', SMALL).repair == THOUSANDTHS


def test_at_512_an_answer_of_518_is_still_read_as_pixels():
    parsed = parse('{"x": 518, "y": 100}')
    assert parsed.repair is None and parsed.status is ParseStatus.OUT_OF_RANGE


def test_a_rescaled_frame_from_the_text_keeps_saying_both_repairs():
    parsed = parse('Image 2 is best. {"x": 0.5, "y": 0.25}', INFERRED)
    assert parsed.selected_image == 2
    assert parsed.repair == f"selected_image 2 taken from the text; {FRACTIONS}"


def test_a_plain_rescale_names_only_the_convention():
    assert parse('{"x": 0.5, "y": 0.25}').repair == FRACTIONS


@pytest.mark.parametrize(("x", "y"), [(0, 101.5), (101.5, 0)])
def test_an_overshoot_with_the_other_value_at_zero_is_still_0_1000(x, y):
    assert parse(f'{{"x": {x}, "y": {y}}}', SMALL).repair == THOUSANDTHS


@pytest.mark.parametrize(("x", "y"), [(-0.5, 101.5), (101.5, -0.5)])
def test_an_overshoot_with_a_negative_value_is_not_repaired(x, y):
    assert parse(f'{{"x": {x}, "y": {y}}}', SMALL).repair is None


def test_a_negation_up_to_30_characters_before_the_declaration_cancels_it():
    assert not declares_1000("not" + " " * 27 + "0-1000")  # 'not' starts 30 characters before
    assert declares_1000("not" + " " * 28 + "0-1000")  # 31: outside the window


def test_a_negation_at_the_very_start_of_the_text_counts():
    assert not declares_1000("not 0-1000")
    assert declares_1000("0-1000 scale")


@pytest.mark.parametrize(("x", "y"), [(1.5, 0.5), (0.5, 1.5)])
def test_a_value_past_1_makes_the_answer_pixels_not_fractions(x, y):
    parsed = parse(f'{{"x": {x}, "y": {y}}}')
    assert parsed.repair is None and (parsed.x, parsed.y) == (x, y)


@pytest.mark.parametrize(("x", "y"), [(1000.0, 50.0), (50.0, 1000.0)])
def test_an_overshoot_of_exactly_1000_is_still_0_1000(x, y):
    parsed = parse(f'{{"x": {x}, "y": {y}}}')
    assert parsed.repair == THOUSANDTHS
    assert 511.0 in (parsed.x, parsed.y)  # the end of the 0-1000 range lands on the last pixel


@pytest.mark.parametrize(("x", "y"), [(1000.5, 50.0), (50.0, 1000.5)])
def test_a_value_past_1000_is_never_read_as_0_1000(x, y):
    parsed = parse(f'{{"x": {x}, "y": {y}}}')
    assert parsed.repair is None and (parsed.x, parsed.y) == (x, y)

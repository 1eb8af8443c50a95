"""The official JSON choice, pinned where the mutation check found it unpinned.

Facts (POVBENCH.md, "How the official runner builds requests"): every ``{...}`` object is read;
among those with the keys, the last whose x, y lie in [0, W-1] x [0, H-1] is taken, else the last
with the keys; a failure leaves the row unanswered. An empty answer and an answer whose objects
lack the keys are both unanswered, each with a reason saying which.
"""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent_plugins.parsers.json_answer import JsonAnswerParser

GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)
INFERRED = AnswerSpec(schema=frame_answer_schema(3, 512, 512), n_frames=3)


def test_with_no_answer_in_range_the_last_object_with_the_keys_is_taken():
    parsed = JsonAnswerParser().parse('first {"x": 900, "y": 900} then {"x": 800, "y": 700}', GIVEN)
    assert (parsed.x, parsed.y) == (800.0, 700.0)
    assert parsed.status is ParseStatus.OUT_OF_RANGE


def test_the_last_object_in_range_wins_over_a_later_one_out_of_range():
    parsed = JsonAnswerParser().parse('{"x": 10, "y": 20} {"x": 30, "y": 40} {"x": 900, "y": 5}', GIVEN)
    assert (parsed.x, parsed.y) == (30.0, 40.0)


# The range is [0, W-1] x [0, H-1], edges included (640 x 480 here, so x and y have their own).
WIDE = AnswerSpec(schema=point_answer_schema(640, 480), width=640, height=480, asks_frame=False)


@pytest.mark.parametrize("point", [(0, 0), (639, 479), (0, 479), (639, 0)])
def test_a_point_on_the_edge_of_the_range_is_in_range(point):
    parsed = JsonAnswerParser().parse(f'{{"x": {point[0]}, "y": {point[1]}}} {{"x": 900, "y": 900}}', WIDE)
    assert (parsed.x, parsed.y) == point
    assert parsed.status is ParseStatus.OK


@pytest.mark.parametrize("point", [(-1, 10), (10, -1), (640, 10), (10, 480), (639.5, 10), (10, 479.5)])
def test_a_point_just_past_the_edge_of_the_range_is_out_of_range(point):
    parsed = JsonAnswerParser().parse(f'{{"x": 5, "y": 6}} {{"x": {point[0]}, "y": {point[1]}}}', WIDE)
    assert (parsed.x, parsed.y) == (5.0, 6.0)


def test_a_blank_answer_is_called_empty():
    for text in ("", "   \n\t "):
        parsed = JsonAnswerParser().parse(text, GIVEN)
        assert parsed.status is ParseStatus.UNPARSEABLE
        assert parsed.reason == "empty answer"


def test_objects_without_the_keys_are_named_as_such():
    parsed = JsonAnswerParser().parse('{"point": [3, 4]}', GIVEN)
    assert parsed.status is ParseStatus.UNPARSEABLE
    assert "numeric x, y" in parsed.reason


def test_text_without_any_object_is_named_as_such():
    parsed = JsonAnswerParser().parse("I think it is near the bed.", GIVEN)
    assert parsed.status is ParseStatus.UNPARSEABLE
    assert parsed.reason == "no readable JSON object in the answer"


def test_given_answers_never_take_a_frame_from_the_text():
    parsed = JsonAnswerParser().parse('Image 2 shows it: {"x": 10, "y": 20}', GIVEN)
    assert parsed.status is ParseStatus.OK and parsed.repair is None and parsed.selected_image is None


def test_a_frame_that_is_no_index_is_quoted_in_the_reason():
    parsed = JsonAnswerParser().parse('{"selected_image": "unsure", "x": 10, "y": 20}', INFERRED)
    assert parsed.selected_image is None
    assert "selected_image 'unsure' is not a frame index" in parsed.reason


def test_a_given_answer_is_never_blamed_for_a_missing_frame():
    parsed = JsonAnswerParser().parse('{"x": 10, "y": 20}', GIVEN)
    assert parsed.status is ParseStatus.OK
    assert "selected_image" not in parsed.reason


def test_the_span_of_a_keyless_answer_is_its_last_object():
    parsed = JsonAnswerParser().parse('{"a": 1} and then {"b": 2}', GIVEN)
    assert parsed.span == '{"b": 2}'

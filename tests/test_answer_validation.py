"""Judging a read point against the answer schema (povagent/answer_validation.py)."""

from __future__ import annotations

import pytest

from povagent.answer_validation import judge, judge_points, relative_to_pixels, validator_for
from povagent.answers import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema

FRAMES = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30, asks_frame=True)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)


def test_validators_are_compiled_once_per_schema():
    schema = frame_answer_schema(30, 512, 512)
    assert validator_for(schema) is validator_for(schema)
    assert validator_for(frame_answer_schema(30, 512, 512)) is validator_for(schema)  # equal schema, same validator


def test_different_schemas_get_different_validators():
    assert validator_for(frame_answer_schema(30, 512, 512)) is not validator_for(frame_answer_schema(10, 512, 512))


def test_an_in_range_answer_is_ok():
    parsed = judge(FRAMES, 10, 20, 3)
    assert (parsed.status, parsed.selected_image, parsed.x, parsed.y, parsed.reason) == (ParseStatus.OK, 3, 10.0, 20.0, "")


def test_the_last_pixel_is_in_range_and_the_next_is_not():
    assert judge(GIVEN, 511, 511).status is ParseStatus.OK
    out = judge(GIVEN, 512, 0)
    assert out.status is ParseStatus.OUT_OF_RANGE and out.reason == "x=512 outside [0, 511]"


def test_a_missing_frame_is_out_of_range_with_the_reason():
    parsed = judge(FRAMES, 10, 20, None)
    assert parsed.status is ParseStatus.OUT_OF_RANGE and "selected_image missing" in parsed.reason
    assert parsed.answered  # a point was read; the scorer decides the frame is unknown


def test_an_unknown_frame_is_out_of_range_and_kept():
    parsed = judge(FRAMES, 10, 20, 31)
    assert parsed.status is ParseStatus.OUT_OF_RANGE and parsed.selected_image == 31
    assert parsed.reason == "selected_image=31 outside [0, 29]"


def test_given_answers_never_carry_a_frame():
    assert judge(GIVEN, 1, 2, 5).selected_image is None


def test_a_repair_makes_a_valid_answer_repaired():
    parsed = judge(GIVEN, 1, 2, repair="rescaled 0-1000 -> pixels")
    assert parsed.status is ParseStatus.REPAIRED and parsed.repair == "rescaled 0-1000 -> pixels"


def test_several_points_are_scored_at_their_centroid_and_kept():
    parsed = judge_points(GIVEN, [(0, 0), (100, 50)])
    assert (parsed.x, parsed.y) == (50.0, 25.0) and parsed.points == [(0.0, 0.0), (100.0, 50.0)]


def test_no_points_is_unparseable():
    assert judge_points(GIVEN, []).status is ParseStatus.UNPARSEABLE


@pytest.mark.parametrize("value, scale, pixels", [(500, 1000, 256.0), (1000, 1000, 511.0), (50, 100, 256.0), (0.25, 1, 128.0), (1200, 1000, 614.4)])
def test_relative_coordinates_map_to_pixels(value, scale, pixels):
    assert relative_to_pixels(value, scale, 512) == pytest.approx(pixels)

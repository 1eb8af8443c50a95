"""Judging a read point against the answer schema (povagent/answers/validation.py)."""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent.answers.validation import judge, judge_points, relative_to_pixels, validator_for

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


# -- the pre-check in front of jsonschema: same results, same messages ---------------------------
import itertools  # noqa: E402
import math  # noqa: E402

from jsonschema import Draft202012Validator  # noqa: E402

from povagent.answers import validation as answer_validation  # noqa: E402
from povagent.answers.validation import compile_precheck, schema_errors  # noqa: E402

_SCHEMAS = [frame_answer_schema(30, 512, 512), point_answer_schema(512, 512), frame_answer_schema(1, 640, 480)]
_VALUES = [-1, -0.5, 0, 0.0, 3, 3.0, 3.5, 29, 30, 479, 511, 511.0, 511.5, 512, 639, 640, 1e9, math.nan, math.inf, True, False, None, "3"]


def _answers():
    for x, y in itertools.product(_VALUES, [0, 511.5, 512, math.nan, True]):
        yield {"x": x, "y": y}
        for frame in (0, 29, 30, -1, 3.0, 2.5, True, None, "1"):
            yield {"x": x, "y": y, "selected_image": frame}
    yield {}
    yield {"selected_image": 0}


def _jsonschema_only(schema, answer):
    errors = sorted(Draft202012Validator(schema).iter_errors(answer), key=lambda e: (list(e.path), e.validator))
    return [(list(e.path), e.validator, e.message) for e in errors]


@pytest.mark.parametrize("schema", _SCHEMAS, ids=["frames-30", "point", "frames-1-640x480"])
def test_the_precheck_never_passes_an_answer_jsonschema_rejects(schema):
    precheck = compile_precheck(schema)
    assert precheck is not None
    passed = 0
    for answer in _answers():
        expected = _jsonschema_only(schema, answer)
        if precheck(answer):
            passed += 1
            assert expected == [], answer
        assert [(list(e.path), e.validator, e.message) for e in schema_errors(schema, answer)] == expected, answer
    assert passed > 10  # the common valid answers do take the fast path


@pytest.mark.parametrize("schema", [
    {"type": "object", "properties": {"x": {"type": "number", "exclusiveMinimum": 0}}},
    {"type": "object", "properties": {"x": {"type": ["number", "null"]}}},
    {"type": "object", "properties": {"x": {"type": "number"}}, "additionalProperties": False},
    {"type": "object", "properties": {"x": {"type": "number", "multipleOf": 2}}},
    {"type": "object", "properties": {"x": {"type": "number", "minimum": -math.inf}}},
    {"type": "array"},
    {"anyOf": [{"type": "object"}]},
])
def test_schemas_of_another_shape_are_left_to_jsonschema(schema):
    assert compile_precheck(schema) is None
    judged = judge(AnswerSpec(schema=schema, asks_frame=False), 3, 4)
    assert judged.status is (ParseStatus.OK if not _jsonschema_only(schema, {"x": 3, "y": 4}) else ParseStatus.OUT_OF_RANGE)


def test_judge_gives_the_same_parse_with_and_without_the_precheck(monkeypatch):
    specs = [FRAMES, GIVEN, AnswerSpec(schema=frame_answer_schema(1, 640, 480), width=640, height=480, n_frames=1)]
    cases = [(x, y, frame, repair) for x in (-1, 0, 10.5, 511, 512, 639.5) for y in (0, 511.5, 512)
             for frame in (None, 0, 3, 30) for repair in (None, "rescaled 0-1000 -> pixels")]
    fast = [judge(spec, x, y, frame, repair=repair, note="n") for spec in specs for x, y, frame, repair in cases]
    monkeypatch.setattr(answer_validation, "compile_precheck", lambda schema: None)
    monkeypatch.setattr(answer_validation, "_by_id", {})
    monkeypatch.setattr(answer_validation, "_by_text", {})
    slow = [judge(spec, x, y, frame, repair=repair, note="n") for spec in specs for x, y, frame, repair in cases]
    assert [p.model_dump() for p in fast] == [p.model_dump() for p in slow]
    assert {p.status for p in fast} == {ParseStatus.OK, ParseStatus.REPAIRED, ParseStatus.OUT_OF_RANGE}

"""Malformed or hostile raw answers become typed non-responses, quickly, in every parser.

Each case here once raised or ran in quadratic time: a parse must never raise, never return a
coordinate that is not a finite number (it could not be scored or written as JSON), and cost
time linear in the answer's length.
"""

from __future__ import annotations

import math
import time

import pytest

import povagent.answers.text as answer_text
from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent.answers.text import MAX_NESTING, find_objects, index_from_digits
from povagent.plugins import build_plugin_host

PARSERS = ["json", "cot", "rescale-1000", "qwen", "gemini", "molmo", "robopoint", "internvl"]
FRAMES = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)


@pytest.fixture(scope="module")
def parsers():
    host = build_plugin_host(entry_points=False)
    return {name: host.create("parser", name, {}) for name in PARSERS}


HOSTILE = {
    "integer-too-long-for-int": '{"selected_image": 1, "x": ' + "9" * 5000 + ', "y": 3}',
    "frame-label-too-long-for-int": '{"selected_image": "Image ' + "7" * 5000 + '", "x": 3, "y": 3}',
    "image-mention-too-long-for-int": "Image " + "4" * 5000 + ' {"x": 3, "y": 3}',
    "superscript-digit-as-molmo2-image": '<points coords="\u00b2 1 500 500">x</points>',
    "robopoint-overflowing-to-infinity": "[(" + "9" * 400 + ", 0.5)]",
    "qwen-overflowing-to-infinity": "point_2d: [" + "9" * 400 + ", 5]",
    "nan-and-infinity": '{"selected_image": 1, "x": NaN, "y": Infinity}',
    "nul-bytes-and-replacement-chars": "\x00\ufffd}{\x00{{]]",
}


@pytest.mark.parametrize("name", PARSERS)
@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_text_gives_a_typed_parse_with_finite_coordinates(parsers, name, case):
    for spec in (FRAMES, GIVEN):
        parsed = parsers[name].parse(HOSTILE[case], spec)
        assert isinstance(parsed.status, ParseStatus)
        if parsed.x is not None:
            assert math.isfinite(parsed.x) and math.isfinite(parsed.y)
        parsed.model_dump_json()  # a row can be written


@pytest.mark.parametrize("name", PARSERS)
def test_a_coordinate_overflowing_to_infinity_is_unparseable_not_an_answer(parsers, name):
    text = '[{"point_2d": [1e999, 5], "point": [1e999, 5]}] {"x": 1e999, "y": 5} [(' + "9" * 400 + ".0, 0.5)]"
    parsed = parsers[name].parse(text, GIVEN)
    assert not parsed.answered and parsed.x is None


def test_an_absurd_frame_index_is_no_index():
    assert index_from_digits("12") == 12
    assert index_from_digits("7" * 5000) is None
    assert index_from_digits("\u00b2") is None  # a digit to str.isdigit, not to int
    assert index_from_digits("\u0663") == 3  # Arabic-Indic three: a decimal digit


def test_deeply_nested_braces_are_read_only_near_the_bottom(monkeypatch):
    calls = []
    real = answer_text.lenient_json
    monkeypatch.setattr(answer_text, "lenient_json", lambda span: calls.append(len(span)) or real(span))
    objects = find_objects("{" * 5000 + '"x": 1, "y": 2' + "}" * 5000)
    assert [o.value for o in objects][:1] == [{"x": 1, "y": 2}]
    assert len(calls) == MAX_NESTING + 1  # not 5,000 ever longer spans


def test_an_answer_nested_a_few_levels_is_still_read():
    objects = find_objects('{"response": {"answer": {"selected_image": 3, "x": 10, "y": 20}}}')
    assert objects[0].value == {"selected_image": 3, "x": 10, "y": 20} and len(objects) == 3


@pytest.mark.parametrize(
    "name, text",
    [
        ("internvl", "<box>" * 20000),  # each unclosed tag once rescanned the rest of the text
        ("json", "{" * 5000 + '"x": 1' + "}" * 5000),
        ("cot", "{}" * 100000),
        ("molmo", '<points coords="1 ' + "9" * 50000 + '">'),
    ],
    ids=["unclosed-box-tags", "deep-nesting", "many-empty-objects", "long-digit-run"],
)
def test_hostile_text_is_parsed_in_linear_time(parsers, name, text):
    # CPU time of this process, not wall time: other processes on a loaded machine do not count
    start = time.process_time()
    parsed = parsers[name].parse(text, FRAMES)
    assert parsed.status is ParseStatus.UNPARSEABLE
    assert time.process_time() - start < 1.0  # quadratic behaviour took 5-35 s here


@pytest.mark.parametrize(
    "text",
    ["{,'" + "a,'" * 50000 + "}", "{*/" + "/*" * 50000 + ":}", "{" + "//" * 50000 + ":}"],
    ids=["unclosed-single-quotes", "unclosed-block-comments", "line-comment-markers"],
)
def test_lenient_reading_of_a_long_object_is_linear(text):
    start = time.process_time()  # this process's CPU time: immune to a loaded machine
    assert answer_text.lenient_json(text) is None
    assert time.process_time() - start < 0.5

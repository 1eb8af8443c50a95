"""Reading answer-like pieces out of free text (povagent/answers/text.py)."""

from __future__ import annotations

import pytest

from povagent.answers.text import (
    coerce_index,
    coerce_number,
    final_line_start,
    find_objects,
    lenient_json,
    mentioned_image,
)


def test_objects_are_found_in_prose_and_ordered_by_their_end():
    objs = find_objects('a {"x": 1} b {"outer": {"x": 2}} c')
    assert [o.value for o in objs] == [{"x": 1}, {"x": 2}, {"outer": {"x": 2}}]
    assert objs[0].span == '{"x": 1}'


def test_an_unclosed_object_is_not_completed():
    assert find_objects('{"x": 1, "y": 31') == []


def test_a_prose_apostrophe_does_not_derail_the_scan():
    assert [o.value for o in find_objects("the robot's view: {\"x\": 3, \"y\": 4}")] == [{"x": 3, "y": 4}]


@pytest.mark.parametrize(
    "text, value",
    [
        ('{"x": 1, "y": 2,}', {"x": 1, "y": 2}),
        ("{'x': 1, 'y': 2}", {"x": 1, "y": 2}),
        ("{x: 1, y: 2}", {"x": 1, "y": 2}),
        ('{"x": \u22125, "y": 2}', {"x": -5, "y": 2}),
        ('{\u201cx\u201d: 1}', {"x": 1}),
        ('{"x": +3, "ok": True, "n": None}', {"x": 3, "ok": True, "n": None}),
        ('{"label": "robot\'s chair", "x": 1,}', {"label": "robot's chair", "x": 1}),
        ("{'label': 'robot's chair', 'x': 1}", {"label": "robot's chair", "x": 1}),
        ('{"x": 120, // centre of the rug\n "y": 340}', {"x": 120, "y": 340}),
        ('{/* pixels */ "x": 1, "url": "http://example.org",}', {"x": 1, "url": "http://example.org"}),
        ('{"x": 10., "y": 20.}', {"x": 10, "y": 20}),
    ],
    ids=[
        "trailing-comma", "single-quotes", "bare-keys", "unicode-minus", "curly-quotes", "python-literals",
        "apostrophe-in-string", "apostrophe-in-single-quoted-string", "line-comment", "block-comment", "trailing-dot",
    ],
)
def test_lenient_json_reads_common_deviations(text, value):
    assert lenient_json(text) == value


def test_lenient_json_gives_none_for_non_json():
    assert lenient_json("{<integer 0-29>}") is None


@pytest.mark.parametrize("value, number", [(3, 3.0), (2.5, 2.5), ("17", 17.0), (" \u221212.5 ", -12.5), ("80px", 80.0)])
def test_numbers_are_read_from_numbers_and_numeric_strings(value, number):
    assert coerce_number(value) == number


@pytest.mark.parametrize("value", [True, None, "left", [1], float("nan"), float("inf"), "1e999", 10**400, -(10**400)])
def test_non_numbers_are_refused(value):
    assert coerce_number(value) is None


@pytest.mark.parametrize("value, index", [(3, 3), (3.0, 3), ("3", 3), ("Image 3", 3), ("image_12", 12)])
def test_frame_indices_are_read_leniently(value, index):
    assert coerce_index(value) == index


@pytest.mark.parametrize("value", [3.5, "three", None, False])
def test_non_indices_are_refused(value):
    assert coerce_index(value) is None


def test_the_selected_image_key_wins_over_image_mentions():
    assert mentioned_image('Image 3 is good, but selected_image: 7 and Image 9') == 7


def test_the_last_image_mention_is_taken():
    assert mentioned_image("Image 2 shows a sofa; Image 11 shows both.") == 11
    assert mentioned_image("no frame named here") is None


def test_the_final_line_skips_blank_and_fence_lines():
    text = 'reasoning\n{"x": 1}\n```\n\n'
    assert text[final_line_start(text):].startswith('{"x": 1}')

"""A number of any size anywhere in an answer is read, never a crash (hypothesis).

A 400-digit frame index once crashed ``povagent parse`` (OverflowError while writing the
reason). Frame indices, coordinates, RoboPoint tuples, 0-1000 values, Qwen and Molmo points and
frames named in prose are all generated here as huge or tiny integers and floats (and
overflowing literals such as ``1e400``), in every parser, for A/B and for Given questions: each
parse is typed, its coordinates finite, and a row holding it can be written.
"""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent.plugins import build_plugin_host
from povagent.results.rows import ResultRow, RowStatus

PARSERS = ["official", "json", "cot", "rescale-1000", "qwen", "gemini", "molmo", "robopoint", "robopoint-official", "internvl"]
FRAMES = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)

#: Where a number can stand in an answer, one template per way the parsers read one.
TEMPLATES = [
    '{{"selected_image": {0}, "x": {1}, "y": {2}}}',
    '{{"selected_image": "Image {0}", "x": {1}, "y": {2}}}',
    'Image {0} shows it. {{"x": {1}, "y": {2}}}',
    "selected_image: {0}, x: {1}, y: {2}",
    "[({1}, {2}), ({2}, {1})]",
    "Frame {0}: [({1}, {2})]",
    '[{{"point_2d": [{1}, {2}], "label": "mug"}}]',
    '{{"selected_image": {0}, "point": [{1}, {2}]}}',
    '<point x="{1}" y="{2}" alt="mug">mug</point>',
    '<points coords="{0} 1 {1} {2}">mug</points>',
    "<ref>mug</ref><box>[[{1}, {2}, {1}, {2}]]</box>",
    '```json\n{{"selected_image": {0}, "x": {1}, "y": {2}}}\n```',
]

huge_int = st.one_of(
    st.integers(min_value=-(10**30), max_value=10**30),
    st.integers(min_value=15, max_value=4000).map(lambda n: 10**n - 1),
    st.integers(min_value=15, max_value=4000).map(lambda n: -(10**n) + 7),
)
number_text = st.one_of(
    huge_int.map(str),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.sampled_from(["1e400", "-1e400", "1e-400", "9" * 400 + ".5", "0." + "9" * 400, "1000.0000001", "999.9999", "1E+308"]),
)


@pytest.fixture(scope="module")
def parsers():
    host = build_plugin_host(entry_points=False)
    return {name: host.create("parser", name, {}) for name in PARSERS}


#: The official readings record an overflowing coordinate as the runner did (infinite, scored
#: at the image edge): only these may return a coordinate that is not finite.
OFFICIAL = {"official", "robopoint-official"}


def assert_typed_and_writable(parsed, name: str) -> None:
    assert isinstance(parsed.status, ParseStatus)
    if parsed.x is not None and name not in OFFICIAL:
        assert math.isfinite(parsed.x) and math.isfinite(parsed.y)
    row = ResultRow(key="k#0", instance_id="k", house_id="h", pair_id="0", direction="up", condition="a",
                    status=RowStatus.PARSE_ERROR, parse=parsed)
    written = row.model_dump_json()
    assert ResultRow.model_validate_json(written).model_dump_json() == written  # written and read back


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(template=st.sampled_from(TEMPLATES), numbers=st.tuples(number_text, number_text, number_text))
def test_any_number_anywhere_in_an_answer_is_read_without_a_crash(parsers, template, numbers):
    text = template.format(*numbers)
    for name, parser in parsers.items():
        for spec in (FRAMES, GIVEN):
            try:
                parsed = parser.parse(text, spec)
            except Exception as exc:  # the property: no parser raises
                pytest.fail(f"{name} raised {type(exc).__name__}: {exc} on {text[:120]!r}")
            assert_typed_and_writable(parsed, name)


@pytest.mark.parametrize("digits", [16, 400, 4000])
def test_the_official_reading_keeps_a_huge_frame_index_and_the_row_is_unanswered(parsers, mini_dataset, digits):
    index = 10**digits - 1
    parsed = parsers["official"].parse(json.dumps({"selected_image": index, "x": 10, "y": 10}), FRAMES)
    assert parsed.selected_image == index  # kept as the integer the model wrote
    assert parsed.status == ParseStatus.OUT_OF_RANGE
    scorer = build_plugin_host(entry_points=False).create("scorer", "official", {})
    instance = mini_dataset.instance("train_house_00000/0/right/a")
    assert scorer.score(instance, parsed, mini_dataset)["answered"] is False  # no such frame: unanswered
    assert f"{digits}-digit integer outside [0, 29]" in parsed.reason
    assert_typed_and_writable(parsed, "official")

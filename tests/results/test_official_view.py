"""The official reading of a row, read without copying the row."""

from __future__ import annotations

import math

import pytest

from povagent.answers.spec import ParsedAnswer
from povagent.results.evaluations import official_parse_error
from povagent.results.official_reading import holds_nan, nan_rows, official_view, officially_read
from povagent.results.rows import OfficialReading, ResultRow, RowStatus
from povagent.run.summary_fields import scored_values

SCORES = {"official": {"answered": True, "l2": 0.5, "l2_strict": 0.5, "gt_in_frame": True, "error_x": 0.1, "error_y": 0.2}}


def _row(reading: OfficialReading | None, **extra: object) -> ResultRow:
    return ResultRow(key="h/1/left/a#0", instance_id="h/1/left/a", house_id="h", pair_id="1", direction="left", condition="a",
                     status=RowStatus.ANSWERED, scores=SCORES, parser="json", official_reading=reading, **extra)  # fmt: skip


@pytest.mark.parametrize(
    "reading",
    [
        None,
        OfficialReading(parser="official", parse=ParsedAnswer(status="unparseable", reason="no JSON")),
        OfficialReading(parser="official", parse=ParsedAnswer(status="ok", x=1.0, y=2.0, selected_image=1), scores=SCORES),
        OfficialReading(parser="official", parse=ParsedAnswer(status="ok", x=math.nan, y=2.0)),
    ],
)
def test_the_view_reads_as_the_copy_reads(reading: OfficialReading | None) -> None:
    row = _row(reading, category="Relative Direction")
    copy, view = officially_read(row), official_view(row)
    assert scored_values(view, "official") == scored_values(copy, "official")
    assert official_parse_error(view) == official_parse_error(copy) and nan_rows([view]) == nan_rows([copy])
    assert view.prediction == copy.prediction and view.status is copy.status and view.official_reading is None
    assert (view.parser, view.parse, view.scores, view.key, view.sentence) == (copy.parser, copy.parse, copy.scores, copy.key, copy.sentence)


@pytest.mark.parametrize(
    ("parse", "nan"),
    [
        (None, False),
        (ParsedAnswer(status="ok", x=1.0, y=2.0), False),
        (ParsedAnswer(status="ok", x=math.nan, y=2.0), True),
        (ParsedAnswer(status="ok", x=1.0, y=math.nan), True),
        (ParsedAnswer(status="unparseable", reason="no JSON"), False),
    ],
)
def test_holds_nan_is_what_nan_rows_finds_of_one_row(parse: ParsedAnswer | None, nan: bool) -> None:
    row = _row(None, parse=parse)
    assert holds_nan(parse) is nan and nan_rows([row]) == ([row.key] if nan else [])

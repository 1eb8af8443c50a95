"""A row's line in ``results.jsonl``."""

from __future__ import annotations

import math

from povagent.answers.spec import ParsedAnswer
from povagent.results.rows import ExchangeRecord, OfficialReading, Prediction, ResultRow, RowStatus, row_line


def test_a_rows_line_is_its_model_dump_json_and_a_newline() -> None:
    rows = [
        ResultRow(key="h/1/left/a#0", instance_id="h/1/left/a", house_id="h", pair_id="1", direction="left", condition="a",
                  status=RowStatus.ANSWERED, sentence="naïve “quotes” \u2028 and \U0001f600",
                  exchanges=[ExchangeRecord(request_hash="ab", image_hashes=["cd"], prompt="--- user ---\nQ?", raw="{\"x\": NaN}", latency_s=1e-05)],
                  parse=ParsedAnswer(status="out_of_range", x=math.nan, y=math.inf, number=None),
                  prediction=Prediction(x=math.nan, y=-math.inf, value={"point": [1.5, 2]}),
                  scores={"official": {"answered": True, "l2": math.nan, "note": "é"}}, cost_usd=-0.0,
                  official_reading=OfficialReading(parser="official", parse=ParsedAnswer(status="unparseable", reason="none")),
                  plugin_field={"kept": [1, 2.5, None]}),
        ResultRow(key="s/7#1", instance_id="s/7", house_id="s", pair_id="7", direction="", condition="", run=1, status=RowStatus.INFRA_ERROR,
                  error_type="timeout", error_message="no answer"),
    ]  # fmt: skip
    for row in rows:
        assert row_line(row, None, checked=False) == row.model_dump_json(exclude_none=False) + "\n"

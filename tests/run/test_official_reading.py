"""A run parsed with a lenient parser keeps the official reading beside it, row by row and in its summary."""

from __future__ import annotations

import json

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

N_KEYS = 12  # 4 (pair, direction)s x 3 conditions in the small release

#: json repairs the trailing comma; the official runner's json.loads refuses the object.
TRAILING_COMMA = '{"selected_image": 1, "x": 100, "y": 200,}'


def run(path):
    result = run_pipeline(load_pipeline(path))
    return result, read_rows(result.run_dir / "results.jsonl")


def reply(text):
    return {"name": "test-center", "options": {"reply": text}}


def test_lenient_rows_record_the_official_reading(write_pipeline):
    _, rows = run(write_pipeline(backend=reply(TRAILING_COMMA), parser="json"))
    assert len(rows) == N_KEYS
    for row in rows:
        assert row.status == "answered" and row.parser == "json"
        reading = row.official_reading
        assert reading is not None and reading.parser == "official"
        assert reading.parse.status == "unparseable" and reading.scores == {}


def test_summary_shows_the_official_response_rate_beside_the_repaired_one(write_pipeline):
    result, _ = run(write_pipeline(backend=reply(TRAILING_COMMA), parser="json"))
    summary = json.loads((result.run_dir / "summary.json").read_text())
    assert summary["overall"]["response_rate"] == 1.0
    official = summary["official_parse"]
    assert official["parser"] == "official" and official["rows_without_reading"] == 0
    assert official["overall"]["response_rate"] == 0.0 and official["overall"]["n_total"] == N_KEYS
    assert official["overall"]["mean_l2"] is None


def test_same_reading_reuses_the_scores(write_pipeline):
    result, rows = run(write_pipeline(backend=reply('{"selected_image": 1, "x": 100, "y": 200}'), parser="json"))
    assert all(r.official_reading.scores == r.scores for r in rows)
    summary = json.loads((result.run_dir / "summary.json").read_text())
    assert summary["official_parse"]["overall"] == summary["overall"]


def test_an_official_parser_records_no_second_reading(write_pipeline):
    result, rows = run(write_pipeline(backend=reply(TRAILING_COMMA), parser="official"))
    assert all(r.official_reading is None and r.status == "parse_error" for r in rows)
    assert "official_parse" not in json.loads((result.run_dir / "summary.json").read_text())


def test_resume_keeps_the_readings_of_earlier_rows(write_pipeline):
    run(write_pipeline(backend=reply(TRAILING_COMMA), parser="json", instances={"limit": 5}))
    result, rows = run(write_pipeline(backend=reply(TRAILING_COMMA), parser="json"))
    assert result.n_pending == N_KEYS - 5
    assert all(r.official_reading is not None for r in rows)
    official = json.loads((result.run_dir / "summary.json").read_text())["official_parse"]
    assert official["overall"]["n_total"] == N_KEYS and official["rows_without_reading"] == 0


def test_a_nan_coordinate_is_stored_as_recorded(write_pipeline):
    _, rows = run(write_pipeline(backend=reply('{"selected_image": 1, "x": NaN, "y": 200}'), parser="official",
                                 instances={"conditions": ["a"], "limit": 1}))
    (row,) = rows
    assert row.parse.x != row.parse.x and row.parse.y == 200  # NaN read back from results.jsonl


def test_rows_without_a_reading_are_counted_not_mixed_in(write_pipeline):
    from povagent.run.summary import summarize_rows

    _result, rows = run(write_pipeline(backend=reply(TRAILING_COMMA), parser="json"))
    older = [r.model_copy(update={"official_reading": None}) for r in rows[:3]]  # as written before readings
    summary = summarize_rows(older + rows[3:])
    official = summary["official_parse"]
    assert official["rows_without_reading"] == 3
    assert official["overall"]["n_total"] == N_KEYS - 3  # left out, never scored with their repaired parse
    assert official["overall"]["response_rate"] == 0.0


def test_a_nan_coordinate_row_is_named_in_the_summary(write_pipeline):
    result, _ = run(write_pipeline(backend=reply('{"selected_image": 1, "x": NaN, "y": 200}'), parser="json",
                                   instances={"conditions": ["a"], "limit": 2}))
    summary = json.loads((result.run_dir / "summary.json").read_text())
    assert len(summary["nan_coordinate_rows"]) == 2  # json refuses NaN; the official reading keeps it

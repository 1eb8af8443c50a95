"""Rows and summaries carry a format version; each older shape reads as the current one, and a
newer one is refused (:mod:`povagent.results.upgrade`).

``tests/fixtures/row_formats`` holds ``format_1.jsonl`` (a point row, a multiple-choice row with
a main category, an infrastructure error, as this release writes them) and one file per era of
format 0: the same rows without the fields that era did not have yet (read from the history of
``povagent/results/rows.py`` on main: ``official_reading`` 2026-11-22 evening; ``model``,
``profile`` and ``exchanges[].prompt`` 2026-11-25, release 0.1.0's shape; ``label``,
``prediction.answer_type``/``value`` and ``exchanges[].prompt_continues`` 2026-11-29, when
multiple-choice rows began; ``category``/``main_category`` 2026-12-07), written as JSON lines.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from povagent.errors import PredictionsError
from povagent.results.finished_run import SUMMARY_FILE, FinishedRun
from povagent.results.rows import CURRENT_ROW_START, ResultRow, ResultsWriter, iter_rows, read_rows, row_line
from povagent.results.upgrade import ROW_FORMAT, ROW_STEPS, SUMMARY_FORMAT
from povagent.run.summary import summarize_rows, write_summary
from povagent.scoring.metrics import row_category

FORMATS = Path(__file__).resolve().parents[1] / "fixtures" / "row_formats"
CURRENT = FORMATS / "format_1.jsonl"
OLD_SUMMARY = Path(__file__).resolve().parents[1] / "fixtures" / "run_before_answer_types" / "summary.json"

#: What each era of format 0 never recorded, as the current shape says "not recorded":
#: ``(top-level fields, prediction fields, exchange fields)``, cumulative from the newest era.
NOT_RECORDED = {
    "format_0_2026-12-07.jsonl": ({}, {}, {}),
    "format_0_2026-11-29.jsonl": ({"main_category": None}, {}, {}),
    "format_0_2026-11-25.jsonl": ({"main_category": None, "label": None}, {"answer_type": None, "value": None}, {"prompt_continues": False}),
    "format_0_2026-11-22_evening.jsonl": (
        {"main_category": None, "label": None, "model": "", "profile": None},
        {"answer_type": None, "value": None},
        {"prompt_continues": False, "prompt": None},
    ),
    "format_0_2026-11-22.jsonl": (
        {"main_category": None, "label": None, "model": "", "profile": None, "official_reading": None},
        {"answer_type": None, "value": None},
        {"prompt_continues": False, "prompt": None},
    ),
}


def current_rows() -> dict[str, dict]:
    return {r.key: r.model_dump(mode="json") for r in read_rows(CURRENT)}


def as_never_recorded(row: dict, top: dict, prediction: dict, exchange: dict) -> dict:
    """``row`` (a current row, as JSON) with what an era never recorded as the upgrade leaves it."""
    out = json.loads(json.dumps(row))
    out.update(top)
    out["prediction"].update(prediction)
    for e in out["exchanges"]:
        e.update(exchange)
    return out


@pytest.mark.parametrize("era", sorted(NOT_RECORDED))
def test_each_older_shape_reads_as_the_current_shape(era):
    expected = current_rows()
    read = {r.key: r.model_dump(mode="json") for r in read_rows(FORMATS / era)}
    assert read and set(read) <= set(expected)
    for key, row in read.items():
        assert row == as_never_recorded(expected[key], *NOT_RECORDED[era]), key
        assert row["format_version"] == ROW_FORMAT


def test_the_era_fixtures_are_every_older_shape_and_older_than_the_current_rows():
    assert sorted(p.name for p in FORMATS.glob("format_0_*.jsonl")) == sorted(NOT_RECORDED)
    for era in NOT_RECORDED:
        for line in (FORMATS / era).read_text(encoding="utf-8").splitlines():
            assert "format_version" not in json.loads(line)


def test_a_choice_row_from_before_rows_recorded_categories_gets_its_scorers_category():
    # 2026-11-29's rows: the choice scorer wrote the category, the row did not
    row = next(r for r in read_rows(FORMATS / "format_0_2026-11-29.jsonl") if r.scores.get("choice"))
    assert row.category == "orientation_viewpoint" and row.main_category is None
    assert row_category(row) == "orientation_viewpoint"


def test_a_current_row_is_sliced_by_the_category_it_records_never_by_its_scores():
    row = read_rows(CURRENT)[0].model_copy(update={"category": None, "scores": {"choice": {"category": "kitchen"}}})
    assert row_category(row) is None


def test_a_current_file_reads_and_writes_back_byte_for_byte():
    data = CURRENT.read_bytes()
    assert b"".join(row_line(r, CURRENT).encode() for r in iter_rows(CURRENT)) == data
    assert all(line.startswith(CURRENT_ROW_START) for line in data.splitlines())


@pytest.mark.parametrize("era", sorted(NOT_RECORDED))
def test_an_older_row_is_written_back_in_the_current_format_and_reads_the_same(era, tmp_path):
    rows = read_rows(FORMATS / era)
    path = tmp_path / "results.jsonl"
    path.write_text("".join(row_line(r, path) for r in rows), encoding="utf-8")
    assert all(line.startswith(CURRENT_ROW_START) for line in path.read_bytes().splitlines())
    assert read_rows(path) == rows


def test_a_file_resumed_by_this_release_holds_both_formats_and_reads_as_one(tmp_path):
    # a run of format 0 resumed: its rows stay as written, the new rows are of format 1
    path = tmp_path / "results.jsonl"
    path.write_bytes((FORMATS / "format_0_2026-11-25.jsonl").read_bytes())
    old = read_rows(path)
    new = read_rows(CURRENT)[1]
    with ResultsWriter(path) as writer:
        writer.write(new)
    assert read_rows(path) == [*old, new]
    assert [line.startswith(CURRENT_ROW_START) for line in path.read_bytes().splitlines()] == [False] * len(old) + [True]


def _with_version(version: object) -> bytes:
    first = json.loads(CURRENT.read_text(encoding="utf-8").splitlines()[0])
    first["format_version"] = version
    return (json.dumps(first) + "\n").encode()


def test_a_newer_row_format_is_refused_with_one_line_naming_the_file_line_and_field(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(CURRENT.read_bytes() + _with_version(ROW_FORMAT + 1))
    with pytest.raises(PredictionsError) as caught:
        read_rows(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: line 4: format_version: {ROW_FORMAT + 1} is newer than this povagent reads")
    assert "\n" not in message


@pytest.mark.parametrize("version", ["1", 1.5, -1, True, None])
def test_a_version_that_is_not_a_whole_number_from_0_is_refused(tmp_path, version):
    path = tmp_path / "results.jsonl"
    path.write_bytes(_with_version(version))
    with pytest.raises(PredictionsError, match=rf"^{re.escape(str(path))}: line 1: format_version: .* is not a format version"):
        read_rows(path)


def test_a_line_that_opens_with_the_current_version_but_says_another_later_is_not_taken_at_its_word(tmp_path):
    line = CURRENT.read_bytes().splitlines()[0]
    path = tmp_path / "results.jsonl"
    path.write_bytes(line[:-1] + b',"format_version":' + str(ROW_FORMAT + 1).encode() + b"}\n")  # JSON: the last one counts
    with pytest.raises(PredictionsError, match="format_version: 2 is newer"):
        read_rows(path)


def test_every_older_version_has_one_step():
    assert [s.version for s in ROW_STEPS] == list(range(ROW_FORMAT))
    assert all(era.__doc__ for step in ROW_STEPS for era in step.eras)


def test_a_row_made_in_code_is_of_the_current_format():
    assert ResultRow(key="k#0", instance_id="k", house_id="h", pair_id="0", direction="", condition="", status="answered").format_version == ROW_FORMAT


def declared_in_summary(summary: Path, folder: Path) -> dict:
    """The metrics the run reader finds declared in ``summary``, as a run folder's own."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / SUMMARY_FILE).write_bytes(summary.read_bytes())
    return FinishedRun(folder).declared


def test_a_written_summary_carries_its_format_version_first(tmp_path):
    summary = write_summary(tmp_path / "summary.json", summarize_rows(read_rows(CURRENT)))
    text = (tmp_path / "summary.json").read_text(encoding="utf-8")
    assert summary.format_version == SUMMARY_FORMAT
    assert text.startswith('{\n  "format_version": ' + str(SUMMARY_FORMAT) + ",")


def test_a_summary_without_a_version_is_read(tmp_path):
    # written before summaries carried a version, and before metrics were declared: none declared
    assert "format_version" not in json.loads(OLD_SUMMARY.read_text(encoding="utf-8"))
    assert declared_in_summary(OLD_SUMMARY, tmp_path) == {}


def test_a_newer_summary_is_refused_with_one_line_naming_the_file_and_field(tmp_path):
    path = tmp_path / "summary.json"
    write_summary(path, summarize_rows(read_rows(CURRENT)))
    data = json.loads(path.read_text(encoding="utf-8"))
    path.write_text(json.dumps({**data, "format_version": SUMMARY_FORMAT + 1}), encoding="utf-8")
    with pytest.raises(PredictionsError) as caught:
        declared_in_summary(path, tmp_path / "run")
    assert str(caught.value).startswith(f"{tmp_path / 'run' / 'summary.json'}: format_version: {SUMMARY_FORMAT + 1} is newer than this povagent reads")
    assert "\n" not in str(caught.value)


#: Phrases that narrate a branch for rows or run folders of an older version.
HISTORY = re.compile(r"written before|rows before|from before|older rows|earlier versions?|older versions?", re.IGNORECASE)
#: Where such a phrase is about something else, with why.
NOT_ROWS = {
    "povagent/results/upgrade.py": "the one place older formats are handled",
    "povagent/engine/request_path.py": "a response cache entry, not a row",
    "povagent/generate/record.py": "a generated house's record, not a run folder",
    "povagent/run/run_folder.py": "the run folder marker, versioned by its own format field",
}


def test_no_reader_outside_the_upgrade_narrates_rows_of_an_older_version():
    root = Path(__file__).resolve().parents[2]
    found = [
        f"{path.relative_to(root)}:{n}: {line.strip()}"
        for folder in ("povagent", "plugins")
        for path in sorted((root / folder).rglob("*.py"))
        if str(path.relative_to(root)) not in NOT_ROWS
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1)
        if HISTORY.search(line)
    ]
    assert not found, "handle an older format in povagent/results/upgrade.py, not in a reader:\n" + "\n".join(found)

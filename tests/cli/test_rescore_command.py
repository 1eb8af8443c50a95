"""``povagent rescore``: re-parse and re-score a finished run offline with another parser."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus, read_rows

runner = CliRunner()

#: (instance, raw answer): Qwen-style answers on 0-1000 although pixels were asked.
ANSWERS = [
    ("train_house_00000/0/right/a", '{"selected_image": 1, "x": 734, "y": 402}'),
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200}'),
    ("train_house_00000/0/left/a", "I cannot tell."),
]


@pytest.fixture
def finished_run(tmp_path, write_answered_run) -> Path:
    """A finished run: the answers above, parsed with json, and one key that failed."""
    run = write_answered_run(tmp_path / "run", ANSWERS)
    with ResultsWriter(run / "results.jsonl") as w:
        w.write(ResultRow(key="train_house_00000/0/left/b#0", instance_id="train_house_00000/0/left/b", house_id="train_house_00000",
                          pair_id="0", direction="left", condition="b", status=RowStatus.INFRA_ERROR, error_type="Timeout"))
    return run


def test_rescore_repairs_rows_and_writes_a_new_folder(tmp_path, mini_root, finished_run):
    run = finished_run
    before = (run / "results.jsonl").read_bytes()
    result = runner.invoke(app, ["rescore", str(run), "--parser", "rescale-1000", "--json"])
    assert result.exit_code == 0, result.output
    rows = {r.instance_id: r for r in read_rows(run / "rescored-rescale-1000" / "results.jsonl")}
    repaired = rows["train_house_00000/0/right/a"]
    assert repaired.parse.status == "repaired" and repaired.parser == "rescale-1000"
    assert (repaired.prediction.x, repaired.prediction.selected_image) == (734 / 1000 * 512, 1)
    assert repaired.prediction.image_path == "exploration_images/frame_001.png"
    assert repaired.scores["official"]["answered"] is True
    assert rows["train_house_00000/0/right/c"].parse.status == "ok"  # in range: never "repaired"
    assert rows["train_house_00000/0/left/a"].status == RowStatus.PARSE_ERROR
    assert rows["train_house_00000/0/left/b"].status == RowStatus.INFRA_ERROR
    assert (run / "results.jsonl").read_bytes() == before


def test_rescore_writes_and_prints_the_summary(tmp_path, mini_root, finished_run):
    run = finished_run
    result = runner.invoke(app, ["rescore", str(run), "--parser", "rescale-1000", "--json"])
    printed = json.loads(result.stdout)
    saved = json.loads((run / "rescored-rescale-1000" / "summary.json").read_text())
    assert printed == saved
    assert saved["overall"]["n"] == 2 and saved["overall"]["n_total"] == 4
    assert saved["repaired"] == 1 and saved["parser"] == "rescale-1000"
    config = yaml.safe_load((run / "rescored-rescale-1000" / "config.yaml").read_text())
    assert config["parser"]["name"] == "rescale-1000"


def test_rescore_with_the_same_parser_reproduces_the_parse(tmp_path, mini_root, finished_run):
    run = finished_run
    assert runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"]).exit_code == 0
    row = {r.instance_id: r for r in read_rows(run / "rescored-json" / "results.jsonl")}["train_house_00000/0/right/a"]
    assert row.parse.status == "out_of_range" and row.prediction.x == 734


def test_rescore_of_a_folder_without_results_is_a_clear_error(tmp_path):
    result = runner.invoke(app, ["rescore", str(tmp_path), "--parser", "json"])
    assert result.exception is not None and "results.jsonl" in str(result.exception)


def test_rescore_reads_a_config_resolved_from_a_model_profile(tmp_path, mini_root, finished_run):
    run = finished_run
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["model"] = "qwen3-vl-32b"  # a resolved config keeps the profile name beside its backend
    (run / "config.yaml").write_text(yaml.safe_dump(config))
    assert runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"]).exit_code == 0


def test_a_relative_dataset_path_not_found_here_says_where_to_run_from(tmp_path, mini_root, monkeypatch, finished_run):
    from povagent.errors import DatasetError

    run = finished_run
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["dataset"]["path"] = "tests/fixtures/povbench_mini"  # as written by a run made from the repo root
    (run / "config.yaml").write_text(yaml.safe_dump(config))
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["rescore", str(run), "--parser", "json"])
    assert isinstance(result.exception, DatasetError)
    assert "relative path 'tests/fixtures/povbench_mini'" in str(result.exception) and "--dataset" in str(result.exception)
    ok = runner.invoke(app, ["rescore", str(run), "--parser", "json", "--dataset", str(mini_root), "--json"])
    assert ok.exit_code == 0, ok.output


def test_rescore_makes_no_model_call(tmp_path, mini_root, monkeypatch, finished_run):
    from povagent.plugins import PluginHost

    create = PluginHost.create

    def create_but_no_backend(self, kind, name, options=None):
        assert kind != "backend", "rescore created a backend"
        return create(self, kind, name, options)

    monkeypatch.setattr(PluginHost, "create", create_but_no_backend)
    run = finished_run
    result = runner.invoke(app, ["rescore", str(run), "--parser", "rescale-1000", "--json"])
    assert result.exit_code == 0, result.output


# -- the official reading: the default, and beside every lenient one -------------------------------
#: Answers the official runner reads otherwise than json: a trailing comma (unanswered), a
#: self-correction ending in a null frame (unanswered), and a NaN coordinate (kept as NaN).
LENIENT_ANSWERS = [
    ("train_house_00000/0/right/a", '{"selected_image": 1, "x": 100, "y": 200,}'),
    ("train_house_00000/0/left/a", '{"selected_image": 1, "x": 50, "y": 60} Actually: {"selected_image": null, "x": 70, "y": 80}'),
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200}'),
    ("train_house_00000/0/left/c", '{"x": NaN, "y": 200}'),
]


@pytest.fixture
def run_with(finished_run):
    """``run_with(answers)``: the finished run with these answers written last (last row wins)."""

    def write(answers) -> Path:
        return _append(finished_run, answers)

    return write


def _append(run: Path, answers) -> Path:
    with ResultsWriter(run / "results.jsonl") as w:
        for inst_id, raw in answers:
            house, pair, direction, cond = inst_id.split("/")
            w.write(ResultRow(key=f"{inst_id}#0", instance_id=inst_id, house_id=house, pair_id=pair, direction=direction,
                              condition=cond, status=RowStatus.ANSWERED, parser="json",
                              exchanges=[ExchangeRecord(request_hash="h", raw=raw)]))
    return run


def test_rescore_defaults_to_the_official_reading(tmp_path, mini_root, run_with):
    run = run_with(LENIENT_ANSWERS)
    result = runner.invoke(app, ["rescore", str(run), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads((run / "rescored-official" / "summary.json").read_text())
    assert summary["parser"] == "official" and "official_parse" not in summary
    rows = {r.instance_id: r for r in read_rows(run / "rescored-official" / "results.jsonl")}
    assert rows["train_house_00000/0/right/a"].status == RowStatus.PARSE_ERROR  # trailing comma
    assert rows["train_house_00000/0/left/a"].status == RowStatus.PARSE_ERROR  # the chosen frame is null
    assert all(r.official_reading is None for r in rows.values())


def test_a_lenient_rescore_keeps_the_official_reading_beside(tmp_path, mini_root, run_with):
    run = run_with(LENIENT_ANSWERS)
    result = runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads((run / "rescored-json" / "summary.json").read_text())
    official = summary["official_parse"]
    assert official["parser"] == "official" and official["rows_without_reading"] == 0
    # json answers 2 of 6 rows in A (trailing comma repaired; the null frame leaves no frame), official 0
    assert summary["per_condition"]["a"]["n"] == 1 and official["per_condition"]["a"]["n"] == 0
    rows = {r.instance_id: r for r in read_rows(run / "rescored-json" / "results.jsonl")}
    assert rows["train_house_00000/0/right/a"].official_reading.parse.status == "unparseable"
    assert rows["train_house_00000/0/right/c"].official_reading.scores == rows["train_house_00000/0/right/c"].scores


def test_the_console_shows_the_official_parse_beside_a_lenient_one(tmp_path, mini_root, run_with):
    run = run_with(LENIENT_ANSWERS)
    result = runner.invoke(app, ["rescore", str(run), "--parser", "json"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "Official parse beside 'json' (repaired)" in result.stdout
    assert "L2 official (official)" in result.stdout and "resp. official" in result.stdout
    official = runner.invoke(app, ["rescore", str(run)])
    assert "Official parse beside" not in official.stdout


def test_rows_with_a_nan_coordinate_are_named_in_a_warning(tmp_path, mini_root, run_with):
    run = run_with(LENIENT_ANSWERS)
    result = runner.invoke(app, ["rescore", str(run)])
    assert result.exit_code == 0, result.output
    assert "NaN coordinate" in result.stderr and "train_house_00000/0/left/c#0" in result.stderr
    rows = {r.instance_id: r for r in read_rows(run / "rescored-official" / "results.jsonl")}
    nan_row = rows["train_house_00000/0/left/c"]
    assert nan_row.parse.x != nan_row.parse.x  # recorded as NaN, as the official runner records it

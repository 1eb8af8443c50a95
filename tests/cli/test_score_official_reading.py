"""``povagent score`` on our run folders reports the official reading by default."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()

#: json answers both (it repairs the trailing comma); the official runner only the second.
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200,}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 100}'),
]


@pytest.fixture
def lenient_run(tmp_path, write_answered_run):
    """A run parsed with json whose raw answers the official reading sees differently."""
    return write_answered_run(tmp_path / "run", ANSWERS)


def score(path, mini_root):
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout), result.stderr


def test_score_reads_a_lenient_run_by_its_official_reading(tmp_path, mini_root, lenient_run):
    run = lenient_run
    assert runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"]).exit_code == 0
    summary, _ = score(run / "rescored-json", mini_root)
    assert summary["overall"]["n"] == 1 and summary["overall"]["n_total"] == 2  # json itself answers 2


def test_rows_without_a_reading_are_scored_as_parsed_with_a_warning(tmp_path, mini_root, lenient_run):
    run = lenient_run
    assert runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"]).exit_code == 0
    rows = (run / "rescored-json" / "results.jsonl").read_text().splitlines()
    stripped = [json.dumps({**json.loads(line), "official_reading": None}) for line in rows]
    (run / "rescored-json" / "results.jsonl").write_text("\n".join(stripped) + "\n")
    summary, err = score(run / "rescored-json", mini_root)
    assert summary["overall"]["n"] == 2
    assert "carry no official reading" in err and "rescore RUN --parser official" in err


def test_score_names_rows_with_a_nan_coordinate(tmp_path, mini_root, lenient_run):
    run = lenient_run
    lines = (run / "results.jsonl").read_text().splitlines()
    nan_row = json.loads(lines[1])
    nan_row["exchanges"][0]["raw"] = '{"x": NaN, "y": 100}'
    (run / "results.jsonl").write_text("\n".join([lines[0], json.dumps(nan_row)]) + "\n")
    assert runner.invoke(app, ["rescore", str(run), "--json"]).exit_code == 0
    _, err = score(run / "rescored-official", mini_root)
    assert "NaN coordinate" in err and "train_house_00000/0/left/c#0" in err

"""The report puts the official parse beside the numbers of a system parsed leniently."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.report.build import write_report
from povagent.report.collect import collect
from povagent.report.official_beside import official_beside_table

runner = CliRunner()

#: json answers all three (trailing comma repaired, single quotes read); the official runner one.
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200,}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 100}'),
    ("train_house_00000/0/front/c", "{'x': 200, 'y': 300}"),
]


@pytest.fixture
def run_parsed_with(tmp_path, write_answered_run):
    """``run_parsed_with(parser)``: the answers above, rescored with ``parser``."""

    def rescored(parser: str):
        run = write_answered_run(tmp_path / "raw", ANSWERS)
        assert runner.invoke(app, ["rescore", str(run), "--parser", parser, "--json"]).exit_code == 0
        return run / f"rescored-{parser}"

    return rescored


def test_a_lenient_system_gets_its_official_numbers_beside(tmp_path, mini_root, run_parsed_with):
    table = official_beside_table(collect(run_parsed_with("json")))
    assert table is not None
    names = [c.name for c in table.columns]
    assert names == ["Given L2 repaired", "Given resp. repaired", "Given L2 official", "Given resp. official"]
    (row,) = table.rows
    assert "(json)" in row.label
    assert row.cells[1].value == 1.0 and abs(row.cells[3].value - 1 / 3) < 1e-12


def test_an_official_system_is_not_listed(tmp_path, mini_root, run_parsed_with):
    assert official_beside_table(collect(run_parsed_with("official"))) is None


def test_the_report_writes_the_table(tmp_path, mini_root, run_parsed_with):
    folder = run_parsed_with("json")
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=50)
    text = (tmp_path / "report" / "tables" / "official_parse_beside.md").read_text()
    assert "Official parse beside the repaired numbers" in text
    assert any(t.key == "official_parse_beside" for t in result.tables)

"""The report puts the official parse beside the numbers of a system parsed leniently."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.report.build import write_report
from povagent.report.collect import collect
from povagent.report.official_beside import official_beside_table
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus

runner = CliRunner()

#: json answers all three (trailing comma repaired, single quotes read); the official runner one.
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200,}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 100}'),
    ("train_house_00000/0/front/c", "{'x': 200, 'y': 300}"),
]


def run_parsed_with(tmp_path, mini_root, parser: str):
    run = tmp_path / "raw"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "backend": {"name": "center", "options": {}},
        "strategy": {"name": "basic", "options": {}},
        "parser": {"name": "json", "options": {}},
        "scorers": [{"name": "official", "options": {}}],
        "output": str(run),
    }))
    with ResultsWriter(run / "results.jsonl") as w:
        for inst_id, raw in ANSWERS:
            house, pair, direction, cond = inst_id.split("/")
            w.write(ResultRow(key=f"{inst_id}#0", instance_id=inst_id, house_id=house, pair_id=pair, direction=direction,
                              condition=cond, status=RowStatus.ANSWERED, parser="json",
                              exchanges=[ExchangeRecord(request_hash="h", raw=raw)]))
    assert runner.invoke(app, ["rescore", str(run), "--parser", parser, "--json"]).exit_code == 0
    return run / f"rescored-{parser}"


def test_a_lenient_system_gets_its_official_numbers_beside(tmp_path, mini_root):
    table = official_beside_table(collect(run_parsed_with(tmp_path, mini_root, "json")))
    assert table is not None
    names = [c.name for c in table.columns]
    assert names == ["Given L2 repaired", "Given resp. repaired", "Given L2 official", "Given resp. official"]
    (row,) = table.rows
    assert "(json)" in row.label
    assert row.cells[1].value == 1.0 and abs(row.cells[3].value - 1 / 3) < 1e-12


def test_an_official_system_is_not_listed(tmp_path, mini_root):
    assert official_beside_table(collect(run_parsed_with(tmp_path, mini_root, "official"))) is None


def test_the_report_writes_the_table(tmp_path, mini_root):
    folder = run_parsed_with(tmp_path, mini_root, "json")
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=50)
    text = (tmp_path / "report" / "tables" / "official_parse_beside.md").read_text()
    assert "Official parse beside the repaired numbers" in text
    assert any(t.key == "official_parse_beside" for t in result.tables)

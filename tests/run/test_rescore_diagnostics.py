"""``povagent rescore RUN --scorer diagnose --scorer relation``: the diagnostics of a finished
run, offline (the model's server sees no request)."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.results.rows import read_rows
from povagent.run.runner import PipelineRun
from povagent.testing.loopback_server import LoopbackServer

KEY_ENV = "POVAGENT_DIAGNOSTICS_TEST_KEY"
runner = CliRunner()


@pytest.fixture
def served_run(tmp_path, mini_root, monkeypatch):
    """A run of a 'model' on a loopback server (always frame 1, pixel (200, 300)), official scorer
    only; yields (run folder, server) with the server still up."""
    monkeypatch.setenv(KEY_ENV, "test-key")
    with LoopbackServer(reply=json.dumps({"selected_image": 1, "x": 200, "y": 300}), max_lifetime_s=120) as server:
        config = pipeline_from_source(ConfigSource("<test>", {
            "dataset": {"path": str(mini_root)},
            "backend": {"name": "litellm", "options": {"model": "openai/loopback", "api_base": server.url, "api_key_env": KEY_ENV}},
            "scorers": ["official"], "cache": False, "output": str(tmp_path / "run"),
        }, {}))  # fmt: skip
        asyncio.run(PipelineRun(config).run())
        assert server.requests, "the run itself asked the model"
        yield tmp_path / "run", server


def test_rescoring_with_diagnose_and_relation_makes_no_request(served_run):
    run, server = served_run
    before = len(server.requests)
    result = runner.invoke(app, ["rescore", str(run), "--scorer", "diagnose", "--scorer", "relation", "--json"])
    assert result.exit_code == 0, result.output
    assert len(server.requests) - before == 0
    summary = json.loads((run / "rescored-official" / "summary.json").read_text())
    cells = summary["diagnostics"]["per_condition"]
    assert set(cells) == {"a", "b", "c"} and "not in the paper" in summary["diagnostics"]["label"]
    for cond, cell in cells.items():
        assert cell["n_diagnosed"] > 0 and abs(sum(cell["failure_steps"].values()) - 1.0) < 1e-9, cond
        assert 0.0 <= cell["relation_success"] <= 1.0
        assert set(cell["per_direction"]) <= {"right", "left", "front", "up"}
    assert cells["c"]["egocentric_bias"] is None
    rows = [r for r in read_rows(run / "rescored-official" / "results.jsonl") if r.status == "answered"]
    assert rows and all({"official", "diagnose", "relation"} <= set(r.scores) for r in rows)
    config = yaml.safe_load((run / "rescored-official" / "config.yaml").read_text())
    assert [s["name"] for s in config["scorers"]] == ["official", "diagnose", "relation"]


def test_the_console_prints_the_additions_under_the_official_table(served_run):
    run, _ = served_run
    result = runner.invoke(app, ["rescore", str(run), "--scorer", "diagnose", "--scorer", "relation"])
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "Additions (not in the paper)" in out and "viewpoint" in out
    assert out.index("re-parsed with official") < out.index("strict") < out.index("Additions (not in the paper)")


def test_without_the_scorers_there_is_no_diagnostics_section(served_run):
    run, _ = served_run
    result = runner.invoke(app, ["rescore", str(run), "--json"])
    assert result.exit_code == 0, result.output
    assert "diagnostics" not in json.loads(result.stdout)
    assert "Additions" not in runner.invoke(app, ["rescore", str(run)]).stdout


def test_an_unknown_scorer_is_refused_by_name(served_run, command_forks):
    run, _ = served_run
    done = command_forks.run("rescore", run, "--scorer", "diagnoze", cwd=Path.cwd(), timeout=120)
    assert done.returncode == 2 and "unknown scorer 'diagnoze' (did you mean 'diagnose'?)" in done.stderr
    assert not (run / "rescored-official" / "results.jsonl").exists()

"""A report over rows holding a number that is not finite (a model that answered NaN, scored by
``relation``) writes its page and its ``summary.json``: summaries write such a number as JSON's
``null``, the general way, never a file that stops half-way or is not JSON."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.results.summary_json import finite_json, summary_json_text
from povagent.testing.loopback_server import LoopbackServer

pytestmark = pytest.mark.timeout(240)


def test_a_report_on_a_run_where_relation_met_a_nan_answer_writes_its_summary(generated_release: Path, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-secret-123")
    house = sorted(p.name for p in (generated_release / "artifacts").iterdir() if p.is_dir())[0]
    with LoopbackServer(max_lifetime_s=200) as server:
        server.reply = '{"selected_image": 0, "x": NaN, "y": 100}'
        pipeline = tmp_path / "pipeline.yaml"
        pipeline.write_text(yaml.safe_dump({
            "dataset": str(generated_release),
            "instances": {"houses": [house], "conditions": ["a"]},
            "backend": {"name": "litellm", "options": {"model": "openai/nan", "api_base": server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
            "parser": "official",
            "scorers": ["official", "relation"],
            "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
            "cache": False,
            "output": str(tmp_path / "run"),
        }))  # fmt: skip
        result = CliRunner().invoke(app, ["run", str(pipeline), "--quiet"])
    assert result.exit_code == 0, result.output[-3000:]
    result = CliRunner().invoke(app, ["report", str(tmp_path / "run"), "--out", str(tmp_path / "report"), "--bootstrap", "0"])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 0, result.output[-3000:]
    assert (tmp_path / "report" / "report.html").exists()
    summary = json.loads((tmp_path / "report" / "summary.json").read_text(), parse_constant=lambda name: pytest.fail(f"{name} in summary.json"))
    assert summary


def test_a_number_that_is_not_finite_is_written_as_null_wherever_it_sits(tmp_path: Path) -> None:
    data = {"mean": math.nan, "rows": [1.0, math.inf, {"low": -math.inf, "ok": 0.5}], "pair": (math.nan, 2)}
    assert finite_json(data) == {"mean": None, "rows": [1.0, None, {"low": None, "ok": 0.5}], "pair": [None, 2]}
    assert json.loads(summary_json_text(data))["rows"][1] is None

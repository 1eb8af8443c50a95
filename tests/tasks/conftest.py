"""A pipeline over the session's generated set (tests/conftest.py ``generated_release``), asked
as one of the paper's future-work tasks, run through the command line as a user runs it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app


@pytest.fixture
def task_pipeline(tmp_path, generated_release):
    """``task_pipeline(task, backend, **overrides) -> Path``: a pipeline YAML over the generated set."""

    def make(task: Any, backend: str = "oracle", name: str = "pipeline.yaml", **overrides: Any) -> Path:
        data: dict[str, Any] = {
            "dataset": {"path": str(generated_release)},
            "task": task,
            "backend": {"name": backend},
            "strategy": "choice",
            "scorers": ["choice"],
            "concurrency": 4,
            "output": str(tmp_path / name.removesuffix(".yaml")),
        }
        data.update(overrides)
        path = tmp_path / name
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return make


@pytest.fixture
def run_rows():
    """``run_rows(pipeline) -> rows``: run a pipeline with ``povagent run``, return its result rows."""
    return _run_rows


def _run_rows(pipeline: Path) -> list[dict[str, Any]]:
    result = CliRunner().invoke(app, ["run", str(pipeline)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    out = Path(yaml.safe_load(pipeline.read_text())["output"])
    return [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]

"""``task: navigate`` selects the walk: the ``navigate`` strategy and scorer where the pipeline
names none, and a strategy that does not walk is refused at the ``strategy:`` line."""

from __future__ import annotations

import json

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(300)


def write(tmp_path, doc: dict):
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def test_task_navigate_names_the_navigate_strategy_and_scorer_when_the_pipeline_names_none(tmp_path, mini_root):
    config = load_pipeline(write(tmp_path, {"dataset": {"path": str(mini_root)}, "task": "navigate",
                                            "backend": "explorer-oracle", "output": str(tmp_path / "run")}))  # fmt: skip
    assert config.strategy.name == "navigate" and [s.name for s in config.scorers] == ["navigate"]
    assert config.parser is not None and config.parser.name == "navigate"


def test_task_navigate_refuses_a_strategy_that_does_not_walk(tmp_path, mini_root):
    path = write(tmp_path, {"dataset": {"path": str(mini_root)}, "task": "navigate", "backend": "center",
                            "strategy": "basic", "output": str(tmp_path / "run")})  # fmt: skip
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert str(err.value).startswith(f"{path}, line 5: task navigate is walked in active mode, and strategy 'basic' does not walk it")


def test_a_navigate_task_run_walks_and_reports_spl(tmp_path, generated_release):
    path = write(tmp_path, {"dataset": {"path": str(generated_release)}, "task": "navigate",
                            "instances": {"houses": ["train_house_00001"], "sample": 3, "seed": 2},
                            "backend": "explorer-oracle", "output": str(tmp_path / "run")})  # fmt: skip
    run_pipeline(load_pipeline(path))
    summary = json.loads((tmp_path / "run" / "summary.json").read_text(encoding="utf-8"))
    overall = summary["metrics"]["navigate"]["overall"]
    assert overall["success_rate"]["value"] == 1.0 and overall["spl"]["value"] > 0.9

"""The one reader of a finished run folder: what it reads, once, and what it refuses."""

from __future__ import annotations

import json

import pytest

from povagent.config.yaml_reader import MAX_CONFIG_BYTES
from povagent.errors import PredictionsError
from povagent.results import finished_run
from povagent.results.finished_run import FinishedRun
from povagent.scoring.metrics import Metric

NEAR = Metric("near_rate", "higher", "rate", "near", "Near", "answers near the centre", over="all")


def test_a_folder_without_results_is_no_run(tmp_path):
    (tmp_path / "config.yaml").write_text("runs: 1\n", encoding="utf-8")
    with pytest.raises(PredictionsError, match=r"no results\.jsonl \(is this a run folder\?\)"):
        FinishedRun.open(tmp_path)


def test_a_config_that_is_not_yaml_is_one_error_naming_the_file(tmp_path):
    (tmp_path / "results.jsonl").write_text("", encoding="utf-8")
    (tmp_path / "config.yaml").write_text("a: [1, 2\n", encoding="utf-8")
    with pytest.raises(PredictionsError, match=r"config\.yaml: not valid YAML"):
        _ = FinishedRun.open(tmp_path).config


def test_the_summarys_declarations_are_read_once(tmp_path):
    (tmp_path / "results.jsonl").write_text("", encoding="utf-8")
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"metrics": {"test-near": {"declared": {"near_rate": NEAR.describe()}}}}), encoding="utf-8")
    run = FinishedRun.open(tmp_path)
    assert run.declared == {"test-near": (NEAR,)}
    summary.unlink()  # asked again, it is not read again
    assert run.declared == {"test-near": (NEAR,)}


def test_a_file_that_is_no_summary_declares_nothing(tmp_path):
    (tmp_path / "results.jsonl").write_text("", encoding="utf-8")
    (tmp_path / "summary.json").write_text('{"metrics": {"x": {"declared": {"m": {"label": "no better side"}}}}}', encoding="utf-8")
    assert FinishedRun.open(tmp_path).declared == {}


def test_a_run_config_is_bounded_as_every_config_is():
    assert finished_run.MAX_CONFIG_BYTES == MAX_CONFIG_BYTES

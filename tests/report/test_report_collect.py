"""Loading run and sweep folders into observations (povagent/report/collect.py)."""

from __future__ import annotations

import json
import shutil

import pytest

from povagent.errors import PredictionsError
from povagent.report.collect import collect
from povagent.results.rows import read_rows


def test_run_folder_yields_one_observation_per_row(run_dir):
    c = collect(run_dir)
    rows = read_rows(run_dir / "results.jsonl")
    assert len(c.observations) == len(rows) == 36
    assert c.systems == ["mock-a · basic"]  # a model is always named with its strategy


def test_observation_keeps_the_stored_official_score(run_dir):
    c = collect(run_dir)
    rows = {(r.instance_id, r.run): r for r in read_rows(run_dir / "results.jsonl")}
    for o in c.observations:
        off = rows[(o.instance_id, o.run)].scores["official"]
        assert o.answered == bool(off["answered"])
        assert o.l2 == off["l2"]


def test_sweep_index_labels_systems_by_the_axes_that_vary(sweep_dir):
    c = collect(sweep_dir)
    assert c.systems == ["mock-a · basic", "mock-a · cot", "mock-b · basic", "mock-b · cot"]


def test_sweep_without_index_is_found_by_scanning_run_folders(sweep_dir, tmp_path):
    copy = tmp_path / "sweep"
    shutil.copytree(sweep_dir, copy)
    (copy / "sweep.json").unlink()
    assert len(collect(copy).runs) == 4


def test_sweep_index_naming_no_folder_is_reported_with_the_cell(tmp_path):
    (tmp_path / "sweep.json").write_text(json.dumps({"cells": [{"axes": {"model": "x"}}]}))
    with pytest.raises(PredictionsError, match=r"cells\[0\]"):
        collect(tmp_path)


def test_missing_folder_is_a_clear_error(tmp_path):
    with pytest.raises(PredictionsError, match="no such run or sweep folder"):
        collect(tmp_path / "nope")

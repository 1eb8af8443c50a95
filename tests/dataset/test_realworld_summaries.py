"""Run and sweep summaries of a real-world set: success and response rates as the success scorer
judged the rows (the official columns say nothing about a set without official ground truth).

A replayed "model" answers the demo set from official-format rows written here: 3 hits, one
miss in the marked frame, one point in a frame without a mark, and one non-response.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.dataset.realworld_set import success_breakdown
from povagent.report.collect import run_success_breakdown
from povagent.results.rows import iter_rows

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"

#: Pixels in the 512x512 letterboxed frames (1280x720 originals: x * 0.4, y * 0.4 + 112).
ANSWERS = [
    {"house_id": "house_1", "pair_id": "kitchen", "direction": "right", "type": "a",
     "predicted_image": "house_1/frame_01.jpg", "predicted_x": 216.0, "predicted_y": 236.0},   # hit: the point mark
    {"house_id": "house_1", "pair_id": "kitchen", "direction": "right", "type": "b"},          # no answer
    {"house_id": "house_1", "pair_id": "kitchen", "direction": "right", "type": "c",
     "predicted_x": 218.0, "predicted_y": 234.0},                                              # hit: inside the box
    {"house_id": "house_1", "pair_id": "bedroom", "direction": "up", "type": "a",
     "predicted_image": "house_1/frame_02.jpg", "predicted_x": 388.0, "predicted_y": 284.0},   # hit: inside the region
    {"house_id": "house_1", "pair_id": "bedroom", "direction": "up", "type": "c",
     "predicted_x": 20.0, "predicted_y": 130.0},                                               # miss
    {"house_id": "house_1", "pair_id": "study", "direction": "front", "type": "a",
     "predicted_image": "house_1/frame_00.jpg", "predicted_x": 256.0, "predicted_y": 256.0},   # frame without a mark
]


def povagent(*args: str, cwd: Path) -> str:
    """Run the CLI (wide terminal, so rich tables keep one line per row); its stdout."""
    env = os.environ | {"COLUMNS": "200", "NO_COLOR": "1"}
    done = subprocess.run([sys.executable, "-m", "povagent.cli", *args], capture_output=True, text=True, cwd=cwd, env=env, timeout=180)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def table_row(text: str, label: str) -> list[str]:
    """The cells of the rich table row starting with ``label``."""
    for line in text.splitlines():
        cells = [c.strip() for c in re.split(r"[│┃]", line)[1:-1]]
        if cells and cells[0] == label:
            return cells[1:]
    raise AssertionError(f"no row {label!r} in:\n{text}")


@pytest.fixture(scope="module")
def setup(tmp_path_factory) -> Path:
    base = tmp_path_factory.mktemp("realworld_summaries")
    (base / "answers.json").write_text(json.dumps(ANSWERS), encoding="utf-8")
    (base / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(DEMO)}, "backend": {"name": "replay", "options": {"path": str(base / "answers.json")}},
        "strategy": "basic", "parser": "json", "scorers": ["success"], "output": str(base / "run"),
    }))
    (base / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "pipeline.yaml", "output": str(base / "sweep"),
        "axes": {"backend": ["center", {"name": "replay", "options": {"path": str(base / "answers.json")}}]},
    }))
    return base


@pytest.fixture(scope="module")
def sweep_output(setup) -> str:
    return povagent("sweep", "sweep.yaml", "-q", cwd=setup)


def test_sweep_summary_shows_the_success_scorers_response_rate_and_success(sweep_output):
    # columns: mean L2, resp. rate, answered / total, success rate
    assert table_row(sweep_output, "replay") == ["-", "83.3%", "5 / 6", "50.0%"]
    assert table_row(sweep_output, "center") == ["-", "100.0%", "6 / 6", "0.0%"]


def test_each_finished_sweep_cell_prints_success_and_response_rate(sweep_output):
    assert "replay: success rate 50.0%, response rate 83.3%" in sweep_output
    assert "mean L2" not in sweep_output.split("sweep sweep.yaml")[0]  # no official error per cell


def test_run_summary_shows_response_rates_beside_success_per_slice(setup):
    out = povagent("run", "pipeline.yaml", "-q", cwd=setup)
    # columns: success rate, hits / total, resp. rate, answered / total
    assert table_row(out, "overall") == ["50.0%", "3 / 6", "83.3%", "5 / 6"]
    assert table_row(out, "Stated (B)") == ["0.0%", "0 / 1", "0.0%", "0 / 1"]
    assert table_row(out, "Inferred (A)") == ["66.7%", "2 / 3", "100.0%", "3 / 3"]
    assert "mean L2" not in out


def test_run_breakdown_counts_unscored_rows_as_unanswered_failures(setup, sweep_output):
    run_dir = setup / "sweep" / "replay"
    rows = list(iter_rows(run_dir / "results.jsonl"))
    assert [r.status for r in rows].count("parse_error") == 1 and all("success" in r.scores or r.status != "answered" for r in rows)
    table = run_success_breakdown(run_dir)
    expected = success_breakdown({"condition": r.condition, "direction": r.direction, **(r.scores.get("success") or {})} for r in rows)
    for part in ("overall", "per_condition", "per_direction"):
        for key, cell in (expected[part].items() if part != "overall" else [("", expected[part])]):
            got = table[part][key] if key else table[part]
            assert got["success_rate"] == cell["success_rate"] and got["n_total"] == cell["n_total"]
    assert table["overall"]["n_answered"] == 5 and table["overall"]["response_rate"] == pytest.approx(5 / 6)


def test_success_breakdown_reports_response_rates_only_when_rows_say_so():
    rows = [{"condition": "a", "direction": "up", "success": True, "answered": True},
            {"condition": "a", "direction": "up", "success": False, "answered": False}]
    assert success_breakdown(rows)["overall"] == {"n_total": 2, "n_success": 1, "success_rate": 0.5, "n_answered": 1, "response_rate": 0.5}
    assert "response_rate" not in success_breakdown([{k: v for k, v in r.items() if k != "answered"} for r in rows])["overall"]


def test_summary_json_of_a_real_world_run_carries_success_and_response_rate(setup, sweep_output):
    summary = json.loads((setup / "sweep" / "replay" / "summary.json").read_text(encoding="utf-8"))
    overall = summary["success"]["overall"]
    assert (overall["n_success"], overall["n_answered"], overall["n_total"]) == (3, 5, 6)
    assert overall["response_rate"] == pytest.approx(5 / 6)
    assert summary["success"]["per_condition"]["b"]["response_rate"] == 0.0

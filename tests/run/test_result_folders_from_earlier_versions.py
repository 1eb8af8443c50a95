"""A run folder written by an earlier povagent (``tests/fixtures/run_before_answer_types``: rows
with x/y predictions and no answer type) still rescores to its own scores and still reports."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

from typer.testing import CliRunner

from povagent.cli import app
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run

BEFORE = Path(__file__).resolve().parents[1] / "fixtures" / "run_before_answer_types"
SCORED_FIELDS = {"status", "parse", "prediction", "scores", "official_reading"}
RUN_ONLY = {"pipeline", "complete", "interrupted", "stopped", "session", "images"}
RESCORE_ONLY = {"source_run", "parser", "n_rows", "parse_status", "repaired"}


def copy_of_the_old_run(tmp_path: Path) -> Path:
    folder = tmp_path / "old_run"
    shutil.copytree(BEFORE, folder)
    return folder


#: Official score fields added since the fixture was written: they come beside the old ones.
OFFICIAL_FIELDS_ADDED_SINCE = {"l2_center"}


def without_fields_added_since(row: dict) -> dict:
    """``row``'s scored fields without the official score fields added since."""
    for scores in (row["scores"], (row.get("official_reading") or {}).get("scores") or {}):
        official = scores.get("official")
        if official is not None:
            scores["official"] = {k: v for k, v in official.items() if k not in OFFICIAL_FIELDS_ADDED_SINCE}
    return row


def test_an_old_run_rescores_to_the_scores_and_summary_it_was_written_with(tmp_path, mini_root):
    folder = copy_of_the_old_run(tmp_path)
    result = rescore_run(folder, "json", dataset_root=mini_root)
    typed = {"prediction": {"answer_type", "value"}}  # new since: the old rows' x/y are what it reads
    old = {r.key: r.model_dump(mode="json", include=SCORED_FIELDS, exclude=typed) for r in read_rows(folder / "results.jsonl")}
    new_rows = read_rows(result.out_dir / "results.jsonl")
    new = {r.key: without_fields_added_since(r.model_dump(mode="json", include=SCORED_FIELDS, exclude=typed)) for r in new_rows}
    assert new == old
    assert all(r.prediction.value == {"selected_image": r.prediction.selected_image, "x": r.prediction.x, "y": r.prediction.y}
               for r in new_rows)
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    rescored = json.loads((result.out_dir / "summary.json").read_text(encoding="utf-8"))
    # the sections it was written with (a section added since, such as metrics, comes beside them);
    # it summed its rows in file order, povagent now in its keys' digest order: a float may differ
    # in its last bit, nothing else may
    assert same_but_the_last_bits({k: v for k, v in rescored.items() if k in summary}, {k: v for k, v in summary.items() if k not in RUN_ONLY})


def same_but_the_last_bits(a, b) -> bool:
    """``a == b``, but that floats may differ by a few units in their last place."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_but_the_last_bits(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_but_the_last_bits(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-14, abs_tol=0.0)
    return type(a) is type(b) and a == b


def test_an_old_run_reports(tmp_path, mini_root):
    folder = copy_of_the_old_run(tmp_path)
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(folder), "--dataset", str(mini_root), "--out", str(out), "--bootstrap", "0", "--no-gallery"])
    assert result.exit_code == 0, result.output
    assert "center" in (out / "report.html").read_text(encoding="utf-8")

"""Prediction files and folders: find the runs under a path, read each, and score them.

``povagent score PATH`` reads predictions here: an official predictions file or run folder, a
prediction root holding one folder per run (``<model>_<run>``, as ``run_all_eval.py`` finds
them), or our own run folder or ``results.jsonl``. The scoring itself is the pure
:mod:`povagent.scoring.predictions`; this module is the file side of it.
"""

from __future__ import annotations

import json
import re
from collections import defaultdict
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from povagent.dataset.loader import Dataset
from povagent.errors import PredictionsError
from povagent.results.official_format import NOT_PREDICTIONS, read_official_run
from povagent.scoring.official_release import OfficialRelease
from povagent.scoring.prediction_summary import summary_of
from povagent.scoring.predictions import (
    RUN_FOLDER_NAME,
    SKIPPED_RUN_FOLDER_SUFFIX,
    ScoredPrediction,
    listing,
    score_official_run,
    score_result_rows,
)

if TYPE_CHECKING:
    from povagent.interfaces import Scorer


def run_folder_label(name: str) -> tuple[str, str]:
    """``(model, run)`` of an official run folder's name, as ``run_all_eval.py`` reads it:
    ``POVBench_gemini25_0`` -> ``("gemini25", "0")``; no ``_<digits>`` suffix -> run ``"-"``."""
    short = re.sub(r"^POVBench_", "", name)
    m = RUN_FOLDER_NAME.match(short)
    return (m.group(1), m.group(2)) if m else (short, "-")


def _has_official_predictions(folder: Path) -> bool:
    return any(p.name not in NOT_PREDICTIONS for p in folder.glob("predictions*.json"))


def run_folders(root: Path) -> list[Path]:
    """The run folders of a prediction root, as ``run_all_eval.py`` finds them (sorted; a folder
    ending in ``_vs`` is skipped) plus folders holding our ``results.jsonl``."""
    if not root.is_dir():
        return []
    return sorted(
        d
        for d in root.iterdir()
        if d.is_dir()
        and not d.name.endswith(SKIPPED_RUN_FOLDER_SUFFIX)
        and (_has_official_predictions(d) or (d / "results.jsonl").exists())
    )


def load_predictions(path: str | Path) -> tuple[str, Any]:
    """Read a predictions path: our ``results.jsonl`` (or a run folder) or official rows.

    Returns ``("results", rows)`` or ``("official", OfficialRun)``.
    """
    from povagent.results.rows import read_rows

    p = Path(path)
    if p.is_dir() and (p / "results.jsonl").exists():
        p = p / "results.jsonl"
    if p.is_file() and p.suffix == ".jsonl" and _holds_result_rows(p):
        rows = read_rows(p)
        if not rows:
            raise PredictionsError(f"{p}: no complete result rows")
        return "results", rows
    if not p.exists():
        raise PredictionsError(f"{p}: predictions file or folder not found")
    return "official", read_official_run(p)


def _holds_result_rows(path: Path) -> bool:
    """Whether a JSON-lines file holds our result rows (``key`` and ``status``), not official rows."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if not line.strip():
                continue
            try:
                first = json.loads(line)
            except (json.JSONDecodeError, RecursionError):
                return True  # let the results reader report what it can read
            return isinstance(first, dict) and "key" in first and "status" in first
    return True


def _score_one(path: Path, dataset: Dataset, release: OfficialRelease | None, run_index: int = 0) -> tuple[list[ScoredPrediction], list[str]]:
    kind, loaded = load_predictions(path)
    if kind == "results":
        scored, warnings = score_result_rows(loaded, dataset)
        return scored, warnings
    return score_official_run(loaded, release if release is not None else dataset, run_index)


def score_predictions(
    path: str | Path, dataset: Dataset, release: OfficialRelease | None = None, scorers: Mapping[str, Scorer] | None = None
) -> tuple[dict[str, Any], list[str]]:
    """Score a predictions path against ``dataset``: the summary and any warnings.

    ``path`` is a predictions file, an official run folder, our run folder or results file, or
    a prediction root holding one folder per run (``<model>_<run>``, as ``run_all_eval.py``
    reads it). Several runs give the mean of per-run means (the paper's number) with the pooled
    numbers under ``pooled``; a root with several models gives ``{"models": {model: summary}}``.

    With ``release`` (:func:`povagent.scoring.official_release.read_release` of the same
    folder) official rows are counted exactly as the official scorer counts them; without it,
    against the loaded ``dataset`` (povagent's own counting). Our own rows are scored against
    ``dataset`` either way. ``scorers`` (``{name: the normalized_l2 scorer}``) adds each
    model's ``metrics`` section: its declared metrics over the fields it gives each point
    (:func:`~povagent.scoring.predictions.summary_of`).
    """
    p = Path(path)
    folders = run_folders(p) if p.is_dir() and not (p / "results.jsonl").exists() else []
    if not folders:
        scored, warnings = _score_one(p, dataset, release)
        if not scored:
            raise PredictionsError(f"{path}: no prediction rows to score")
        return summary_of(scored, scorers), warnings
    by_model: dict[str, list[Path]] = defaultdict(list)
    for folder in folders:
        by_model[run_folder_label(folder.name)[0]].append(folder)
    warnings = []
    # a root holding run folders is read as run_all_eval.py reads it: folders only, so a file
    # beside them (a config.json, a summary) is no run and is left alone
    stray = sorted(f.name for f in p.iterdir() if f.is_file() and f.suffix == ".json")
    if stray:
        warnings.append(f"{len(stray)} file(s) beside the run folders ignored, as officially (a root holds one folder per run): {listing(stray)}")
    models: dict[str, dict[str, Any]] = {}
    for model, runs in by_model.items():
        scored = []
        run_ids: dict[tuple[int, int], int] = {}
        for k, folder in enumerate(runs):
            s, w = _score_one(folder, dataset, release)
            # an official run folder is one run; our run folder may hold several (its rows' run)
            scored += [replace(x, run=run_ids.setdefault((k, x.run), len(run_ids))) for x in s]
            warnings += [f"{folder.name}: {m}" for m in w]
        summary = summary_of(scored, scorers)
        summary["run_folders"] = [f.name for f in runs]
        models[model] = summary
    if len(models) == 1:
        return next(iter(models.values())), warnings
    return {"models": models}, warnings

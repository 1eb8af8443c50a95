"""Prediction files and folders: find the runs under a path, read each, and score them.

``povagent score PATH`` reads predictions here: an official predictions file or run folder, a
prediction root holding one folder per run (``<model>_<run>``, as ``run_all_eval.py`` finds
them), or our own run folder or ``results.jsonl``. The scoring rules are the pure
:mod:`povagent.scoring.predictions`; this module is the file side of it: which rows a file holds,
which run each belongs to, and how our own rows read as the official runner would read them.
"""

from __future__ import annotations

import json
import re
from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from povagent.dataset.loader import Dataset
from povagent.errors import PredictionsError
from povagent.results.evaluations import official_parse_error
from povagent.results.official_format import NOT_PREDICTIONS, OfficialRun, read_official_run
from povagent.results.official_reading import official_rows
from povagent.scoring.normalized_l2 import UNANSWERED, answered_in_camera, closest_point_l2, score_point, scoring_frame
from povagent.scoring.official_release import OfficialRelease
from povagent.scoring.prediction_summary import summary_of
from povagent.scoring.predictions import (
    ENTRY_NOT_FOUND,
    RUN_FOLDER_NAME,
    SKIPPED_RUN_FOLDER_SUFFIX,
    ScoredPrediction,
    listing,
    score_official_rows,
    unanswered,
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


def score_official_run(run: OfficialRun, dataset: Dataset | OfficialRelease, run_index: int = 0) -> tuple[list[ScoredPrediction], list[str]]:
    """Score what :func:`read_official_run` read, at its metadata's screen size.

    Files that declare distinct ``metadata.run`` values (``povagent export`` writes one file
    per run) are scored as those runs; otherwise every row belongs to ``run_index``.
    """
    screen = run.screen_size()
    declared = {r.run for r in run.rows}
    numbered = sorted(r for r in declared if r is not None)
    warnings = list(run.warnings)
    groups = [(k, [r for r in run.rows if r.run == k]) for k in numbered] if len(declared) > 1 and None not in declared else [(run_index, run.rows)]
    if len(groups) > 1:
        warnings.append(
            f"the files declare runs {numbered} (metadata.run): scored as separate runs and "
            "averaged per run (the official loader, given this folder, would pool them as one run)"
        )
    scored: list[ScoredPrediction] = []
    for k, rows in groups:
        s, w = score_official_rows([r.data for r in rows], dataset, screen, k, refs=[r.where for r in rows])
        scored += s
        warnings += w
    return scored, warnings


def score_result_rows(rows: Iterable[Any], dataset: Dataset) -> tuple[list[ScoredPrediction], list[str]]:
    """Re-score our own results rows from their stored predictions, each as the official runner
    reads its answer (a row parsed leniently by its recorded official reading); a row whose
    instance is not in the dataset counts as unanswered (as officially), with a warning."""
    scored: list[ScoredPrediction] = []
    unknown: list[str] = []
    rows, warnings = official_rows(rows)
    for row in rows:
        inst = dataset.instance(row.instance_id)
        if inst is None:
            unknown.append(row.key)
            scored.append(ScoredPrediction(row.instance_id, str(row.condition), str(row.direction), row.run, unanswered(ENTRY_NOT_FOUND)))
            continue
        p = row.prediction
        answered = row.status == "answered" and p.x is not None and p.y is not None
        parse_error = official_parse_error(row) is not None
        if not answered:
            scored.append(ScoredPrediction(inst.id, str(row.condition), str(row.direction), row.run, UNANSWERED, None, parse_error))
            continue
        # an answer given in a camera of its own (an active-mode view) is scored in that camera
        camera = row.parse.camera if row.parse is not None else None
        frame = answered_in_camera(camera) if camera is not None else scoring_frame(inst, p.selected_image, p.image_path)
        points = row.parse.points if row.parse is not None else None
        score = score_point(inst, frame, float(p.x), float(p.y), points[0] if points else None)
        # a multi-point answer's closest point, as the run's scorer recorded it
        closest = closest_point_l2(inst, frame, [(a, b) for a, b in points]) if points and len(points) > 1 and frame is not None else None
        scored.append(ScoredPrediction(inst.id, str(row.condition), str(row.direction), row.run, score, closest, parse_error))
    if unknown:
        warnings.append(
            f"{len(unknown)} row(s) name an instance the dataset does not have; counted in the total as "
            f"unanswered, as officially: {listing(unknown)}"
        )
    return scored, warnings


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

"""Exporting a run's predictions in the official row format (``povagent export``).

The exported file can be scored with the official evaluation code, and read back by
``povagent score`` (through :func:`povagent.results.official_format.read_official_predictions`).
One file per run index: the official format has no run field, and the paper averages runs
scored separately.

Mapping from a result row: ``predicted_x``/``predicted_y`` from the scored prediction (``None``
when unanswered), ``predicted_image`` the selected frame's ``image_path`` (A/B), ``parse_error``
true unless the row was answered, ``predicted_points`` from the parse, ``candidate_images`` the
frames shown (A/B, read from the dataset when it can be loaded).

Reading and writing files only: no scoring here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

from povagent import __version__
from povagent.results.official_format import OfficialPrediction, write_official_predictions
from povagent.results.rows import ResultRow, RowStatus

OFFICIAL_FILE = "official_predictions.json"


def official_row(row: ResultRow, instance: Any = None) -> OfficialPrediction:
    """One result row as an official prediction row."""
    uses_frames = str(row.condition) != "c"
    answered = row.status == RowStatus.ANSWERED and row.prediction.x is not None and row.prediction.y is not None
    image = row.prediction.image_path
    if image is None and uses_frames and instance is not None and row.prediction.selected_image is not None:
        frame = instance.selected_frame(row.prediction.selected_image)
        image = frame.image_path if frame is not None else None
    points = None
    if row.parse is not None and row.parse.points:
        points = [(float(x), float(y)) for x, y in row.parse.points]
    return OfficialPrediction(
        house_id=row.house_id,
        pair_id=row.pair_id,
        direction=row.direction,
        type=row.condition,
        sentence=row.sentence,
        predicted_x=row.prediction.x if answered else None,
        predicted_y=row.prediction.y if answered else None,
        predicted_image=image if uses_frames else None,
        parse_error=not answered,
        predicted_points=points if answered else None,
        candidate_images=[f.image_path for f in instance.frames] if uses_frames and instance is not None else None,
    )


def export_rows(rows: Iterable[ResultRow], dataset: Any = None) -> dict[int, list[OfficialPrediction]]:
    """Official rows per run index, in instance-id order."""
    by_run: dict[int, list[ResultRow]] = {}
    for r in rows:
        by_run.setdefault(r.run, []).append(r)
    out: dict[int, list[OfficialPrediction]] = {}
    for run, rs in sorted(by_run.items()):
        rs.sort(key=lambda r: r.instance_id)
        out[run] = [official_row(r, dataset.instance(r.instance_id) if dataset is not None else None) for r in rs]
    return out


def export_run(run_dir: str | Path, out: str | Path | None = None, run: int | None = None, dataset_path: str | Path | None = None) -> list[Path]:
    """Write a run folder's predictions in the official format; returns the files written.

    ``out`` defaults to ``<run_dir>/official_predictions.json``. With several run indices and no
    ``run`` chosen, ``out`` is a folder holding ``run_<k>.json`` per run.
    """
    from povagent.report.analysis import load_collection_dataset
    from povagent.report.collect import collect

    collection = collect(run_dir)
    if len(collection.runs) != 1:
        raise_many(run_dir, len(collection.runs))
    info = collection.runs[0]
    dataset, _ = load_collection_dataset(collection, dataset_path)
    per_run = export_rows(info.rows, dataset)
    if run is not None:
        per_run = {run: per_run.get(run, [])}
    meta = {
        "exported_by": f"povagent {__version__}",
        "source": str(Path(run_dir)),
        "model": info.axes.get("model"),
        "backend": info.axes.get("backend"),
        "strategy": info.axes.get("strategy"),
        "parser": info.axes.get("parser"),
    }
    target = Path(out) if out is not None else Path(run_dir) / OFFICIAL_FILE
    if len(per_run) == 1:
        (k, rows), = per_run.items()
        return [write_official_predictions(target, rows, meta | {"run": k})]
    folder = target.with_suffix("") if target.suffix == ".json" else target
    return [write_official_predictions(folder / f"run_{k}.json", rows, meta | {"run": k}) for k, rows in per_run.items()]


def raise_many(path: str | Path, n: int) -> None:
    """Export takes one run folder: say so clearly when given a sweep."""
    from povagent.errors import PredictionsError

    raise PredictionsError(f"{path}: holds {n} run folders; export one run folder at a time (e.g. {path}/<cell>)")

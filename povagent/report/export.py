"""Exporting a run's predictions in the official row format (``povagent export``).

The exported file can be scored with the official evaluation code, and read back by
``povagent score`` (through :func:`povagent.results.official_format.read_official_predictions`).
One file per run index: the official format has no run field, and the paper averages runs
scored separately.

Mapping from a result row: ``predicted_x``/``predicted_y`` from the scored prediction (``None``
when unanswered), ``predicted_image`` the selected frame's ``image_path`` (A/B), ``parse_error``
true unless the row was answered, ``predicted_points`` from the parse, ``candidate_images`` the
frames shown (A/B, read from the dataset when it can be loaded).

``--format long-csv`` writes instead the official ``aggregate_runs.py``'s long table
(``all_runs_long.csv``): one line per model, run and item, the same columns in the same order,
values written as that script writes them, so analysis notebooks built on it read ours, with
one exception: a text cell a spreadsheet would run as a formula gets a ``'`` before it
(:mod:`povagent.report.csv_formulas`). Its numbers are the official scorer's per-item record
(:mod:`povagent.results.evaluations`).

Reading and writing files; the numbers come from :mod:`povagent.scoring`.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any, Iterable

from povagent import __version__
from povagent.files.confined_write import write_inside
from povagent.report.csv_formulas import inert
from povagent.results.official_format import OfficialPrediction, write_official_predictions
from povagent.results.rows import ResultRow, RowStatus

OFFICIAL_FILE = "official_predictions.json"
LONG_CSV_FILE = "all_runs_long.csv"

#: The columns of the official long CSV, in its order (notebooks index them by name).
LONG_CSV_COLUMNS: tuple[str, ...] = (
    # Laid out by hand (the formatter is told to skip it): one line per group of columns that
    # belong together (the run, the instance, the prediction, the truth, the errors, the files).
    "model", "run_id", "eval_dir",
    "pair_id", "house_id", "direction", "type",
    "sentence",
    "status", "parse_error",
    "predicted_x", "predicted_y",
    "predicted_x_norm", "predicted_y_norm",
    "gt_x", "gt_y", "gt_in_frame",
    "error_x", "error_y", "error_l2",
    "error_l2_min", "error_l2_mean", "n_points",
    "predicted_image", "camera_image",
    "raw_response",
)  # fmt: skip

#: Columns the official script writes empty when the value is falsy (not only when missing).
_EMPTY_WHEN_FALSY = frozenset({"parse_error", "predicted_image", "camera_image"})


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
    from povagent.report.collect import collect
    from povagent.report.run_sets import load_collection_dataset

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
    # the default lies in the run folder (untrusted): nothing below it is followed; an --out
    # the user typed is theirs to place
    root = Path(run_dir) if out is None else None
    if len(per_run) == 1:
        (k, rows), = per_run.items()
        return [write_official_predictions(target, rows, meta | {"run": k}, root=root)]
    folder = target.with_suffix("") if target.suffix == ".json" else target
    return [write_official_predictions(folder / f"run_{k}.json", rows, meta | {"run": k}, root=root or folder) for k, rows in per_run.items()]


def raise_many(path: str | Path, n: int) -> None:
    """Export takes one run folder: say so clearly when given a sweep."""
    from povagent.errors import PredictionsError

    raise PredictionsError(f"{path}: holds {n} run folders; export one run folder at a time (e.g. {path}/<cell>)")


# -- the long CSV ---------------------------------------------------------------------------------
def long_csv_line(record: dict[str, Any], model: str, run_id: int, eval_dir: str, raw_response: str) -> dict[str, Any]:
    """One line of the long CSV from an item's official evaluation record.

    A value the record lacks (or holds as ``None``) is written empty; ``parse_error``,
    ``predicted_image`` and ``camera_image`` are also empty when falsy, as officially. Other
    values are written as Python prints them (``0.1234...``, ``True``), as the ``csv`` module does.
    """
    given = {"model": model, "run_id": run_id, "eval_dir": eval_dir, "raw_response": raw_response}
    line: dict[str, Any] = {}
    for column in LONG_CSV_COLUMNS:
        value = given[column] if column in given else record.get(column)
        if value is None or (column in _EMPTY_WHEN_FALSY and not value):
            value = ""
        line[column] = value
    return line


def _item_order(dataset: Any) -> dict[tuple[str, str], int]:
    """Pairs in release order (houses sorted, pairs in file order), as the official runner visits them."""
    order: dict[tuple[str, str], int] = {}
    for house_id in sorted(dataset.houses):
        for pair_id in dataset.houses[house_id].pairs:
            order[(house_id, pair_id)] = len(order)
    return order


def long_csv_lines(rows: Iterable[ResultRow], dataset: Any, model: str, eval_dir: str) -> list[dict[str, Any]]:
    """The long CSV's lines for one run folder's rows: by run, then item in release order.

    ``run_id`` counts from 1, as the official runs are numbered (our run index 0 is run 1).
    """
    from povagent.results.evaluations import official_evaluation, raw_response

    order = _item_order(dataset)
    unknown = len(order)

    def key(r: ResultRow) -> tuple[Any, ...]:
        # within a pair the official runner goes direction by direction (sorted), then a, b, c
        return (r.run, order.get((r.house_id, r.pair_id), unknown), r.house_id, r.pair_id, r.direction, str(r.condition))

    return [
        long_csv_line(official_evaluation(r, dataset), model, r.run + 1, eval_dir, raw_response(r))
        for r in sorted(rows, key=key)
    ]


def write_long_csv(path: str | Path, lines: Iterable[dict[str, Any]]) -> Path:
    """Write lines under the official header (UTF-8, the ``csv`` module's default dialect).

    A text cell a spreadsheet would run as a formula (a model's answer ``=HYPERLINK(...)``) is
    written with a ``'`` before it; numbers are written as they are
    (:mod:`povagent.report.csv_formulas` states the rule).

    Written aside and renamed, never through a link planted at ``path`` (the default lies in
    an untrusted run folder): see :mod:`povagent.files.confined_write`.
    """
    path = Path(path)
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=list(LONG_CSV_COLUMNS))
    writer.writeheader()
    writer.writerows({column: inert(value) for column, value in line.items()} for line in lines)
    write_inside(path.parent, path.name, text.getvalue())
    return path


def export_long_csv(
    source: str | Path,
    out: str | Path | None = None,
    *,
    dataset_path: str | Path | None = None,
    model: str | None = None,
    run: int | None = None,
) -> Path:
    """Write ``all_runs_long.csv`` for a run folder or a sweep folder (every cell); returns its path.

    ``model`` labels a single run folder's lines (default: its model, as the official script
    names a model folder; a sweep's cells: their system labels, as reports name them, model and
    strategy); ``run`` keeps one run index. The dataset is
    the runs' own (``dataset_path`` overrides it): the official record needs the ground truth.
    ``out`` defaults to ``<source>/all_runs_long.csv``.
    """
    from povagent.errors import PredictionsError
    from povagent.report.collect import collect

    collection = collect(source)
    if not collection.runs:
        raise PredictionsError(f"{source}: no run folder (results.jsonl) found")
    if model is not None and len(collection.runs) > 1:
        raise PredictionsError(
            f"{source}: --model labels one run folder, and this holds {len(collection.runs)}; their lines are "
            "labelled by the sweep axes that vary (export a single cell to choose its label)"
        )
    datasets: dict[Path | None, Any] = {}
    lines: list[dict[str, Any]] = []
    for info in collection.runs:
        where = Path(dataset_path) if dataset_path is not None else info.dataset_path
        if where not in datasets:
            datasets[where] = _release_dataset(where, info.folder)
        rows = [r for r in info.rows if run is None or r.run == run]
        default = info.system if len(collection.runs) > 1 else info.axes.get("model")
        label = model if model is not None else default or info.name
        lines += long_csv_lines(rows, datasets[where], label, str(info.folder))
    if not lines:
        raise PredictionsError(f"{source}: no result rows{'' if run is None else f' for run {run}'} to export")
    # the official script orders runs by model label, then run number
    lines.sort(key=lambda line: (line["model"], line["run_id"]))
    return write_long_csv(Path(out) if out is not None else Path(source) / LONG_CSV_FILE, lines)


def _release_dataset(path: Path | None, run_folder: Path) -> Any:
    """The release-layout dataset a run used, loaded; a clear error when it cannot be."""
    from povagent.dataset.evaluation_set import format_of
    from povagent.dataset.loader import load_dataset
    from povagent.errors import DatasetError, PredictionsError

    if path is None:
        raise PredictionsError(f"{run_folder}: its config.yaml names no dataset folder; pass --dataset (the release it ran on)")
    found = format_of(path, None)
    if found.official_scorer != "official":  # a set scored otherwise (a real-world set's 2D marks) has no such numbers
        raise PredictionsError(
            f"{run_folder}: ran on {found.docs_row.name} ({path}); the long CSV holds the official scorer's "
            "numbers, which need a POVBench release (its 3D ground truth)"
        )
    try:
        return load_dataset(path, check_images=False)  # the ground truth only
    except DatasetError as exc:
        raise PredictionsError(f"{run_folder}: its dataset cannot be loaded for the ground truth ({exc}); pass --dataset") from exc

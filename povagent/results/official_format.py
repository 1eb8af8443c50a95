"""Reading and writing predictions in the official POVBench evaluation format.

The official format is one row per instance::

    {house_id, pair_id, direction, type ("a"|"b"|"c"), sentence, predicted_x, predicted_y,
     predicted_image (A/B: the frame's image_path), parse_error, predicted_points,
     candidate_images}

A file holds either a list of rows or ``{"metadata": {...}, "predictions": [...]}``; a folder
of such files is read as one list. Rows are tolerant (extra keys are kept and ignored, ids may
be numbers, the type may be upper-case) and strict where a mistake would corrupt scores (an
unknown direction or type, a coordinate that is not a number). Bad input raises
:class:`povagent.errors.PredictionsError` naming the file and the row index.

This module only reads and writes the format: it never scores, never resolves a frame against
a dataset (see :meth:`povagent.dataset.instances.Instance.frame_by_path`) and never touches
the network.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Iterable, Mapping

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from povagent.dataset.instances import instance_id
from povagent.dataset.models import Condition, Direction
from povagent.errors import PredictionsError

#: File name suffixes read from a predictions folder.
PREDICTION_SUFFIXES = (".json", ".jsonl")


class OfficialPrediction(BaseModel):
    """One row of an official predictions file.

    ``predicted_x``/``predicted_y`` are pixels; ``None`` means no prediction. ``parse_error``
    is kept as written (the official tools store a flag or a message). Extra keys are kept.
    """

    model_config = ConfigDict(extra="allow")

    house_id: str
    pair_id: str
    direction: Direction
    type: Condition
    sentence: str | None = None
    predicted_x: float | None = None
    predicted_y: float | None = None
    predicted_image: str | None = None
    parse_error: bool | str | None = None
    predicted_points: list[tuple[float, float]] | None = None
    candidate_images: list[str] | None = None

    @field_validator("house_id", "pair_id", mode="before")
    @classmethod
    def _id_as_str(cls, value: Any) -> Any:
        # pair ids are written as numbers by some tools; bool is an int in Python, not an id
        if isinstance(value, int) and not isinstance(value, bool):
            return str(value)
        return value

    @field_validator("type", "direction", mode="before")
    @classmethod
    def _lower(cls, value: Any) -> Any:
        return value.strip().lower() if isinstance(value, str) else value

    @field_validator("predicted_x", "predicted_y", mode="before")
    @classmethod
    def _empty_is_none(cls, value: Any) -> Any:
        # some exporters write "" or NaN for "no prediction"
        if value == "" or (isinstance(value, float) and math.isnan(value)):
            return None
        return value

    @property
    def instance_id(self) -> str:
        """The instance id ``house/pair/direction/condition`` this row answers."""
        return instance_id(self.house_id, self.pair_id, self.direction, self.type)

    @property
    def has_point(self) -> bool:
        """True when the row carries a finite predicted pixel (the frame is not checked here)."""
        return (
            self.predicted_x is not None
            and self.predicted_y is not None
            and math.isfinite(self.predicted_x)
            and math.isfinite(self.predicted_y)
        )


def _rows_of(doc: Any, file: Path) -> tuple[list[Any], str]:
    """The row list of a parsed document and the JSON path prefix used in messages."""
    if isinstance(doc, list):
        return doc, ""
    if isinstance(doc, Mapping) and "predictions" in doc:
        rows = doc["predictions"]
        if not isinstance(rows, list):
            raise PredictionsError(f"{file}: 'predictions' must be a list of rows, got {type(rows).__name__}")
        return rows, "predictions"
    raise PredictionsError(
        f"{file}: expected a list of prediction rows or an object with 'predictions', "
        f"got {type(doc).__name__}"
        + (f" with keys {sorted(doc)[:8]}" if isinstance(doc, Mapping) else "")
    )


def _validation_message(err: ValidationError) -> str:
    parts = []
    for e in err.errors()[:4]:
        field = ".".join(str(p) for p in e["loc"]) or "(row)"
        parts.append(f"field '{field}': {e['msg']}")
    return "; ".join(parts)


def _parse_rows(raw_rows: Iterable[tuple[int, Any]], file: Path, prefix: str) -> list[OfficialPrediction]:
    rows: list[OfficialPrediction] = []
    for index, raw in raw_rows:
        where = f"{file}: row {index}" + (f" ({prefix}[{index}])" if prefix else "")
        if not isinstance(raw, Mapping):
            raise PredictionsError(f"{where}: expected an object, got {type(raw).__name__}")
        try:
            rows.append(OfficialPrediction.model_validate(raw))
        except ValidationError as exc:
            raise PredictionsError(f"{where}: {_validation_message(exc)}") from None
    return rows


def read_predictions_file(file: str | Path) -> list[OfficialPrediction]:
    """Rows of one predictions file (JSON list, ``{metadata, predictions}``, or JSON lines)."""
    file = Path(file)
    try:
        text = file.read_text(encoding="utf-8")
    except OSError as exc:
        raise PredictionsError(f"{file}: cannot read predictions file ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise PredictionsError(f"{file}: not a UTF-8 text file") from None
    if file.suffix == ".jsonl":
        numbered: list[tuple[int, Any]] = []
        for n, line in enumerate(text.splitlines()):
            if not line.strip():
                continue
            try:
                numbered.append((len(numbered), json.loads(line)))
            except json.JSONDecodeError as exc:
                raise PredictionsError(f"{file}: line {n + 1}: invalid JSON ({exc.msg})") from None
            except RecursionError:
                raise PredictionsError(f"{file}: line {n + 1}: JSON nested too deeply") from None
        return _parse_rows(numbered, file, "")
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PredictionsError(f"{file}: invalid JSON at line {exc.lineno} column {exc.colno} ({exc.msg})") from None
    except RecursionError:
        raise PredictionsError(f"{file}: JSON nested too deeply to be a predictions file") from None
    raw_rows, prefix = _rows_of(doc, file)
    return _parse_rows(enumerate(raw_rows), file, prefix)


def read_predictions_metadata(file: str | Path) -> dict[str, Any]:
    """The ``metadata`` object of a ``{metadata, predictions}`` file (``{}`` for a bare list)."""
    file = Path(file)
    try:
        doc = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise PredictionsError(f"{file}: cannot read predictions metadata ({exc})") from None
    meta = doc.get("metadata") if isinstance(doc, Mapping) else None
    return dict(meta) if isinstance(meta, Mapping) else {}


def prediction_files(path: str | Path) -> list[Path]:
    """The files a predictions path stands for: the file itself, or a folder's JSON files sorted by name."""
    p = Path(path)
    if p.is_file():
        return [p]
    if p.is_dir():
        files = sorted(f for f in p.iterdir() if f.is_file() and f.suffix in PREDICTION_SUFFIXES)
        if not files:
            raise PredictionsError(f"{p}: folder holds no predictions files (*.json, *.jsonl)")
        return files
    raise PredictionsError(f"{p}: no such predictions file or folder")


def read_official_predictions(path: str | Path) -> list[OfficialPrediction]:
    """Every row of an official predictions file or folder, in file then row order.

    Raises :class:`PredictionsError` naming the file and row index on bad input.
    """
    rows: list[OfficialPrediction] = []
    for file in prediction_files(path):
        rows.extend(read_predictions_file(file))
    return rows


def looks_like_official_predictions(file: str | Path) -> bool:
    """Cheap check: is this JSON file an official predictions file (vs. our results rows)?

    True for a list whose first element has ``predicted_x`` or ``type``, or an object with
    ``predictions``. Never raises.
    """
    try:
        doc = json.loads(Path(file).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        return False
    if isinstance(doc, Mapping):
        return "predictions" in doc
    return bool(doc) and isinstance(doc, list) and isinstance(doc[0], Mapping) and (
        "predicted_x" in doc[0] or "type" in doc[0]
    )


def official_document(rows: Iterable[OfficialPrediction], metadata: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The ``{metadata, predictions}`` document for ``rows`` (JSON-able)."""
    return {
        "metadata": dict(metadata or {}),
        "predictions": [r.model_dump(mode="json") for r in rows],
    }


def write_official_predictions(
    path: str | Path, rows: Iterable[OfficialPrediction], metadata: Mapping[str, Any] | None = None
) -> Path:
    """Write ``rows`` as a ``{metadata, predictions}`` file; returns the path written."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_text(json.dumps(official_document(rows, metadata), indent=1) + "\n", encoding="utf-8")
    tmp.replace(p)  # atomic: a reader never sees half a file
    return p

"""Reading and writing predictions in the official POVBench evaluation format.

The official format is one row per instance::

    {house_id, pair_id, direction, type ("a"|"b"|"c"), sentence, predicted_x, predicted_y,
     predicted_image (A/B: the frame's image_path), parse_error, predicted_points,
     candidate_images}

A file holds either a list of rows or ``{"metadata": {...}, "predictions": [...]}``; a folder
of such files is read as one list.

Two readers, for two jobs:

- :func:`read_official_run` reads a file or folder exactly as the official scorer's loader
  does, for scoring (``povagent score``): rows are kept as written (a ``type`` of ``"A"`` stays
  ``"A"``), a folder's ``*.json`` files are read in name order except ``meta.json`` and
  ``eval_results.json`` (which the official flow writes beside the predictions), ``.jsonl``
  files in a folder are ignored, an unreadable file or an object without ``predictions`` is
  skipped, and the metadata (``screen_width``/``screen_height``) is found where the official
  loader finds it. Everything skipped is said in a warning.
- :func:`read_official_predictions` validates rows into :class:`OfficialPrediction` models for
  the tools that need typed rows (replay, import): tolerant (extra keys are kept, ids may be
  numbers, the type may be upper-case) and strict where a mistake would corrupt an answer (an
  unknown direction or type, a coordinate that is not a number). Bad input raises
  :class:`povagent.errors.PredictionsError` naming the file and the row index.

This module only reads and writes the format: it never scores, never resolves a frame against
a dataset (see :meth:`povagent.dataset.instances.Instance.frame_by_path`) and never touches
the network.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from povagent.dataset.instances import instance_id
from povagent.dataset.release_models import Condition, Direction
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


def official_document(rows: Iterable[OfficialPrediction], metadata: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The ``{metadata, predictions}`` document for ``rows`` (JSON-able)."""
    return {
        "metadata": dict(metadata or {}),
        "predictions": [r.model_dump(mode="json") for r in rows],
    }


def write_official_predictions(
    path: str | Path, rows: Iterable[OfficialPrediction], metadata: Mapping[str, Any] | None = None,
    root: str | Path | None = None,
) -> Path:
    """Write ``rows`` as a ``{metadata, predictions}`` file; returns the path written.

    Written aside and renamed (a reader never sees half a file), never through a link planted
    at ``path`` or in a folder between ``root`` (the folder the user named, default ``path``'s
    own) and it: see :mod:`povagent.files.confined_write`.
    """
    from povagent.files.confined_write import write_inside

    p = Path(path)
    base = Path(root) if root is not None else p.parent
    write_inside(base, p.relative_to(base), json.dumps(official_document(rows, metadata), indent=1) + "\n")
    return p


# -- the official loader, reproduced for scoring -------------------------------------------------

#: Files the official evaluation flow keeps in a run folder that are not predictions.
NOT_PREDICTIONS = frozenset({"meta.json", "eval_results.json"})

#: Top-level keys the official loader takes as a folder file's metadata when it has no
#: ``metadata`` object (the official runner writes its predictions files that way).
TOP_LEVEL_METADATA = ("screen_width", "screen_height", "vlm", "types")

#: The frame size the official scorer assumes when the metadata does not give one.
DEFAULT_SCREEN = 512


@dataclass(frozen=True)
class RawPrediction:
    """One prediction row as written (``data``), with the file and index it came from.

    ``run`` is the run index the file declares in ``metadata.run`` (files written by
    ``povagent export``), ``None`` otherwise.
    """

    data: Any
    file: Path
    index: int
    run: int | None = None

    @property
    def where(self) -> str:
        """``file: row i`` for messages."""
        return f"{self.file.name}: row {self.index}"


@dataclass
class OfficialRun:
    """What the official loader reads from a predictions file or folder."""

    rows: list[RawPrediction]
    metadata: dict[str, Any]
    files: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    #: Where the metadata came from (for messages); ``None`` when there is none.
    metadata_file: Path | None = None

    def screen_size(self) -> tuple[float, float]:
        """``(screen_width, screen_height)`` of the metadata, 512 each when absent (as officially).

        Raises :class:`PredictionsError` when a value is not a positive number: the official
        scorer cannot divide by it, so there is no official number to reproduce.
        """
        out = []
        for key in ("screen_width", "screen_height"):
            value = self.metadata.get(key, DEFAULT_SCREEN)
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0
            if not ok:
                where = self.metadata_file or "predictions"
                raise PredictionsError(f"{where}: metadata '{key}' must be a positive number of pixels, got {value!r}")
            out.append(float(value))
        return out[0], out[1]


def _run_of(meta: Any) -> int | None:
    run = meta.get("run") if isinstance(meta, Mapping) else None
    return run if isinstance(run, int) and not isinstance(run, bool) else None


def _folder_metadata(doc: Mapping[str, Any]) -> dict[str, Any]:
    """A folder file's metadata as the official loader takes it: its ``metadata`` object when
    that is non-empty, else its top-level size, model and types keys."""
    meta = doc.get("metadata")
    if meta:
        return dict(meta) if isinstance(meta, Mapping) else {}
    return {k: doc[k] for k in TOP_LEVEL_METADATA if k in doc}


def _rows_in(doc: Any, file: Path, run_warnings: list[str]) -> tuple[list[Any], int | None]:
    """The rows a parsed document contributes, and the run its metadata declares."""
    if isinstance(doc, list):
        return doc, None
    if isinstance(doc, Mapping):
        if "predictions" not in doc:
            run_warnings.append(f"{file}: an object without 'predictions' (keys {sorted(map(str, doc))[:6]}): no rows read from it")
            return [], None
        rows = doc["predictions"]
        if not isinstance(rows, list):
            run_warnings.append(f"{file}: 'predictions' is {type(rows).__name__}, not a list: no rows read from it")
            return [], None
        return rows, _run_of(doc.get("metadata"))
    run_warnings.append(f"{file}: holds a JSON {type(doc).__name__}, neither a list of rows nor an object with 'predictions': skipped")
    return [], None


def _load_json(file: Path) -> Any:
    return json.loads(file.read_text(encoding="utf-8"))


def read_official_run(path: str | Path) -> OfficialRun:
    """Read predictions as the official scorer's loader reads them (see the module docstring).

    A folder: every ``*.json`` file in name order, ``meta.json`` and ``eval_results.json``
    skipped, ``.jsonl`` and other files ignored; a list contributes its rows, an object its
    ``predictions``; the metadata is the first object's ``metadata`` (or, lacking one, its
    top-level ``screen_width``/``screen_height``/``vlm``/``types``). A file: a list (no
    metadata) or an object (its ``predictions`` and ``metadata`` object only). A JSON-lines
    file named directly is read line by line (a povagent extension; the official loader reads
    JSON only). Unreadable files are skipped with a warning; nothing is normalised.
    """
    p = Path(path)
    warnings: list[str] = []
    rows: list[RawPrediction] = []
    if p.is_dir():
        files = sorted(f for f in p.glob("*.json") if f.name not in NOT_PREDICTIONS)
        skipped = sorted(f.name for f in p.glob("*.json") if f.name in NOT_PREDICTIONS)
        if skipped:
            warnings.append(f"{p}: skipped {', '.join(skipped)} (written by the official evaluation, not predictions)")
        ignored = sorted(f.name for f in p.glob("*.jsonl"))
        if ignored:
            warnings.append(f"{p}: ignored {', '.join(ignored)} (a folder is read as the official loader reads it: *.json only)")
        meta: dict[str, Any] = {}
        meta_file: Path | None = None
        read: list[Path] = []
        for f in files:
            try:
                doc = _load_json(f)
            except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
                warnings.append(f"{f}: unreadable, skipped ({type(exc).__name__}: {exc})")
                continue
            read.append(f)
            found, run = _rows_in(doc, f, warnings)
            rows.extend(RawPrediction(r, f, i, run) for i, r in enumerate(found))
            if isinstance(doc, Mapping) and not meta:
                meta = _folder_metadata(doc)
                meta_file = f if meta else None
        if not read:
            raise PredictionsError(f"{p}: folder holds no readable predictions file (*.json)")
        return OfficialRun(rows, meta, read, warnings, meta_file)
    if not p.is_file():
        raise PredictionsError(f"{p}: no such predictions file or folder")
    if p.suffix == ".jsonl":
        return OfficialRun([RawPrediction(r, p, i) for i, r in enumerate(_jsonl_objects(p))], {}, [p], warnings)
    try:
        doc = _load_json(p)
    except RecursionError:
        raise PredictionsError(f"{p}: JSON nested too deeply to be a predictions file") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise PredictionsError(f"{p}: cannot read predictions ({type(exc).__name__}: {exc})") from None
    found, run = _rows_in(doc, p, warnings)
    declared = doc.get("metadata") if isinstance(doc, Mapping) else None
    meta = dict(declared) if isinstance(declared, Mapping) else {}
    return OfficialRun([RawPrediction(r, p, i, run) for i, r in enumerate(found)], meta, [p], warnings, p if meta else None)


def _jsonl_objects(file: Path) -> list[Any]:
    out: list[Any] = []
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise PredictionsError(f"{file}: cannot read predictions ({exc})") from None
    for n, line in enumerate(text.splitlines()):
        if not line.strip():
            continue
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError as exc:
            raise PredictionsError(f"{file}: line {n + 1}: invalid JSON ({exc.msg})") from None
        except RecursionError:
            raise PredictionsError(f"{file}: line {n + 1}: JSON nested too deeply") from None
    return out

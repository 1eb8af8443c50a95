"""VSI-Bench (``nyu-visionx/VSI-Bench``) records in their published formats: Parquet or JSONL.

Each record is ``{id, dataset, scene_name, question_type, question, options, ground_truth}``:
the scene's video is ``<dataset>/<scene_name>.mp4`` beside the file (``arkitscenes/41069025.mp4``);
``question_type`` is one of the set's ten types, six answered with an option letter
(``options`` a list ``["A. left", "B. right", ...]``, ``ground_truth`` the letter) and four with a
number (``options`` null or empty, ``ground_truth`` the number as text, ``"3.2"``). A numerical
answer's unit is the one its type's questions ask in (:data:`UNITS`). Further columns (the
debiased release's ``pruned``) are ignored.

A record is untrusted: ``dataset`` and ``scene_name`` must be plain names (no ``/``, no ``..``),
so the video path can name nothing outside the set's folder; a record with any field wrong is
left out and named in one :class:`~povagent.dataset.problems.Problem` (file, record, field).
This module reads the file; it never opens a video (see :mod:`.vsibench_set`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.numeric_question import NumericQuestion
from povagent.dataset.choice_sets.external import jsonl_records, sound_items
from povagent.dataset.problems import Problem
from povagent.errors import PovagentError

#: The prompt profile the set is asked in.
PROFILE = "vsibench"
#: The question types answered with an option letter, and those answered with a number.
CHOICE_TYPES = (
    "object_rel_direction_easy",
    "object_rel_direction_medium",
    "object_rel_direction_hard",
    "object_rel_distance",
    "route_planning",
    "obj_appearance_order",
)
NUMBER_TYPES = ("object_abs_distance", "object_counting", "object_size_estimation", "room_size_estimation")
#: The unit each numerical type's questions ask in (a count has none).
UNITS = {"object_abs_distance": "meters", "object_counting": "", "object_size_estimation": "centimeters", "room_size_estimation": "square meters"}
#: The most options a question may list (each ``X. text``, X a capital letter).
MAX_OPTIONS = 26
#: The largest Parquet file read (the published set is about 1 MB).
MAX_PARQUET_BYTES = 256 << 20
MISSING_PYARROW = "reading VSI-Bench's Parquet file needs pyarrow: pip install 'povagent[video]' (or give its JSONL)"

_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,127}")
_OPTION = re.compile(r"([A-Z])\.\s*(.*)", re.DOTALL)


@dataclass(frozen=True)
class SceneQuestion:
    """One record as read: its id, its question (a choice or a numerical one) and its video,
    a path relative to the set's folder."""

    id: str
    question: ChoiceQuestion | NumericQuestion
    video: str


def read_vsibench(file: Path) -> tuple[list[SceneQuestion], list[Problem]]:
    """Every sound record of the Parquet (``.parquet``) or JSONL file, and one problem per bad
    record (a record is named by its line, or its row in a Parquet file)."""
    problems: list[Problem] = []
    records = _parquet_records(file, problems) if file.suffix.lower() == ".parquet" else jsonl_records(file, "VSI-Bench file", problems)
    items: list[SceneQuestion] = sound_items(file, records, scene_question, problems)
    return items, problems


def _parquet_records(file: Path, problems: list[Problem]) -> Iterable[tuple[str, Any]]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise PovagentError(MISSING_PYARROW) from None
    from povagent.files.confined_read import read_regular

    data = read_regular(file, MAX_PARQUET_BYTES, what="VSI-Bench Parquet file")
    try:
        table = pq.read_table(pa.BufferReader(data))
    except (pa.ArrowException, OSError) as exc:
        problems.append(Problem(str(file), "", f"not a readable Parquet file: {str(exc).splitlines()[0][:200]}"))
        return
    for row, record in enumerate(table.to_pylist()):
        yield f"row {row}", record


def scene_question(record: Any, where: str) -> SceneQuestion | tuple[str, str]:
    """The record as a :class:`SceneQuestion`, or ``(where, message)`` saying what is wrong."""
    if not isinstance(record, dict):
        return where, f"a record must be an object (got {type(record).__name__})"
    record_id = record.get("id")
    plain_int = isinstance(record_id, int) and not isinstance(record_id, bool) and record_id >= 0
    if not plain_int and not (isinstance(record_id, str) and _NAME.fullmatch(record_id)):
        return f"{where}.id", f"required, a non-negative integer or a plain name, got {record_id!r:.60}"
    for key in ("dataset", "scene_name"):
        value = record.get(key)
        if not isinstance(value, str) or not _NAME.fullmatch(value) or set(value) == {"."}:
            return f"{where}.{key}", f"required, a plain name (letters, digits, '_', '.', '-'; no '/'), got {value!r:.60}"
    question_type = record.get("question_type")
    if question_type not in CHOICE_TYPES and question_type not in NUMBER_TYPES:
        return f"{where}.question_type", f"{question_type!r:.60} is none of VSI-Bench's ten question types"
    text = record.get("question")
    if not isinstance(text, str) or not text.strip():
        return f"{where}.question", "required, a non-empty string"
    gold = record.get("ground_truth")
    plain_number = isinstance(gold, (int, float)) and not isinstance(gold, bool)
    if not (isinstance(gold, str) and gold.strip()) and not (plain_number and question_type in NUMBER_TYPES):
        return f"{where}.ground_truth", f"required, a non-empty string (a number for a numerical type), got {gold!r:.60}"
    video = f"{record['dataset']}/{record['scene_name']}.mp4"
    if question_type in NUMBER_TYPES:
        number = _gold_number(str(gold))  # the official to_float reads a JSON number as it reads its text
        if number is None:
            return f"{where}.ground_truth", f"{gold!r:.60} is not a finite non-zero number (the MRA divides by it)"
        return SceneQuestion(str(record_id), NumericQuestion(text, number, unit=UNITS[question_type], category=question_type, profile=PROFILE), video)
    options = _options(record.get("options"))
    if isinstance(options, str):
        return f"{where}.options", options
    try:
        choice = ChoiceQuestion(text, options, str(gold).strip(), category=question_type, profile=PROFILE)
    except ValueError as exc:
        return f"{where}.ground_truth", str(exc)
    return SceneQuestion(str(record_id), choice, video)


def _gold_number(text: str) -> float | None:
    """``float(text)`` as the official ``to_float`` reads the gold, if finite and non-zero."""
    try:
        number = float(text)
    except ValueError:
        return None
    return number if math.isfinite(number) and number != 0 else None


def _options(value: Any) -> tuple[tuple[str, str], ...] | str:
    """The options ``(label, text)``, or why ``value`` holds none."""
    if not isinstance(value, list) or not value or not all(isinstance(o, str) for o in value):
        return "required for a multiple-choice type: a list of options 'X. text'"
    if len(value) > MAX_OPTIONS:
        return f"{len(value)} options; a question has at most {MAX_OPTIONS}"
    options = []
    for number, option in enumerate(value):
        match = _OPTION.fullmatch(option.strip())
        if match is None:
            return f"option {number + 1} {option[:60]!r} is not 'X. text'"
        options.append((match.group(1), match.group(2).strip()))
    return tuple(options)

"""MMSI-Bench (``RunsenXu/MMSI-Bench``, CC-BY-NC-4.0 per its README) in its published Parquet file.

``MMSI_Bench.parquet`` holds one row per question, as the set's README reads it: ``id``, ``images``
(the question's images, each the encoded image's bytes; a ``datasets`` ``Image`` struct
``{bytes, path}`` is read too), ``question_type`` (one of the set's eleven task types: the
category), ``question`` (the question with its options inside it: ``... Options: A: Front left,
B: Front right, C: Back left, D: Back right``), ``answer`` (the gold letter) and ``thought`` (the
annotated reasoning, not read). Other columns are left alone.

The images are untrusted bytes: each must be a PNG or a JPEG of at most
:data:`~povagent.files.confined_read.MAX_IMAGE_FILE_BYTES`, and a row at most
:data:`MAX_IMAGES` of them; each is written once, named by its content, into the set's cache
folder, where :mod:`.external` checks it sound (its pixel count bounded) like any image. The
file is read a few rows at a time, and a row group whose columns would decode to far more than
the file holds (:data:`MAX_ROW_GROUP_BYTES`, :data:`EXPANSION`) is refused before it is read.
pyarrow decodes a row group's ``images`` column whole, so reading peaks at about twice the
largest row group in Arrow's memory (the set's file is one row group: about twice the file;
measured in the results notes).

Reading Parquet needs ``pyarrow`` (``pip install pyarrow``). This module never opens an image
file (see :mod:`.external`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any, Iterator

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, cached_image, record_id_problem, sound_items
from povagent.dataset.problems import Problem
from povagent.errors import DatasetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES

#: The prompt profile the set is asked in.
PROFILE = "mmsi"
#: The columns a row must have.
COLUMNS = ("id", "images", "question_type", "question", "answer")
#: The most images a question shows (the set's multi-step questions show a handful).
MAX_IMAGES = 64
#: The most a row group may decode to: this, or :data:`EXPANSION` times the file's size when
#: that is more. Encoded images do not compress further, so a sound file decodes to about its
#: own size (the set's file is written as one row group of every row); a small file declaring
#: far more is a decompression bomb, refused before it is decoded.
MAX_ROW_GROUP_BYTES = 512 << 20
EXPANSION = 4
#: Rows decoded at a time.
BATCH_ROWS = 8
#: How much of a column chunk is read at a time: with no pre-buffering, the pages stream through
#: a buffer this size instead of the whole row group being read first.
BUFFER_BYTES = 1 << 20
MISSING_PYARROW = "reading MMSI_Bench.parquet needs pyarrow: pip install pyarrow"

_OPTIONS_MARK = "Options:"
#: An option's label in the options text: a capital letter and a colon, first or after a comma.
_OPTION_LABEL = re.compile(r"(?:^|,)\s*([A-Z])\s*:\s*")


def inline_options(question: str) -> tuple[tuple[str, str], ...]:
    """The options written after the question's last ``Options:``: the labels ``A:``, ``B:``, ...
    in order (each first in the text or after a comma), each option running to the next label
    (its trailing comma dropped); empty when there is no such run of at least two."""
    at = question.rfind(_OPTIONS_MARK)
    if at == -1:
        return ()
    text = question[at + len(_OPTIONS_MARK) :].strip()
    run: list[re.Match[str]] = []
    for mark in _OPTION_LABEL.finditer(text):
        if ord(mark.group(1)) == ord("A") + len(run):
            run.append(mark)
    if len(run) < 2:
        return ()
    ends = [m.start() for m in run[1:]] + [len(text)]
    return tuple((m.group(1), text[m.end() : end].strip().rstrip(",").strip()) for m, end in zip(run, ends))


def read_mmsi(file: Path, cache: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound row of the Parquet file as an item (its images written into ``cache``), and
    one problem per bad row. :class:`~povagent.errors.DatasetError` when the file is not a
    Parquet file of the set's columns."""
    problems: list[Problem] = []
    rows = ((f"row {number}", row) for number, row in _rows(file, problems))
    return sound_items(file, rows, lambda row, where: _item(row, where, cache), problems, reused="is used by an earlier row"), problems


def _rows(file: Path, problems: list[Problem]) -> Iterator[tuple[int, dict[str, Any]]]:
    """The file's rows, numbered from 1, a few at a time; each row group checked first."""
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise DatasetError(f"{file}: {MISSING_PYARROW}") from None
    from povagent.files.confined_read import open_regular

    with open_regular(file, what="MMSI-Bench file") as handle:
        try:
            parquet = pq.ParquetFile(handle, pre_buffer=False, buffer_size=BUFFER_BYTES)
        except Exception as exc:  # pyarrow's errors (ArrowInvalid, OSError) say what is wrong
            raise DatasetError(f"{file}: not a Parquet file ({type(exc).__name__}: {str(exc)[:200]})") from None
        missing = [c for c in COLUMNS if c not in parquet.schema_arrow.names]
        if missing:
            raise DatasetError(f"{file}: no column {', '.join(missing)} (MMSI_Bench.parquet has {', '.join(COLUMNS)}, thought)")
        number = 0
        bound = max(MAX_ROW_GROUP_BYTES, EXPANSION * os.fstat(handle.fileno()).st_size)
        for group in range(parquet.num_row_groups):
            size = parquet.metadata.row_group(group).total_byte_size
            rows = parquet.metadata.row_group(group).num_rows
            if size > bound:
                problems.append(
                    Problem(
                        str(file),
                        f"rows {number + 1}-{number + rows}",
                        f"a row group declaring {size} bytes, over the {bound} one may decode to; its rows left out",
                    )
                )
                number += rows
                continue
            try:
                for batch in parquet.iter_batches(batch_size=BATCH_ROWS, row_groups=[group], columns=list(COLUMNS)):
                    for row in batch.to_pylist():
                        number += 1
                        yield number, row
            except Exception as exc:  # a corrupt page: the rest of the group cannot be told apart
                problems.append(
                    Problem(str(file), f"row {number + 1}", f"cannot be decoded ({type(exc).__name__}: {str(exc)[:200]}); the rest of its row group left out")
                )
                number = sum(parquet.metadata.row_group(g).num_rows for g in range(group + 1))


def _item(row: dict[str, Any], where: str, cache: Path) -> Item | tuple[str, str]:
    """The row as an item, or ``(where, message)`` saying what is wrong with it."""
    raw_id = row.get("id")
    record_id = str(raw_id) if isinstance(raw_id, int) and not isinstance(raw_id, bool) else raw_id
    id_problem = record_id_problem(record_id)
    if id_problem:
        return f"{where}.id", id_problem
    assert isinstance(record_id, str)
    question = row.get("question")
    if not isinstance(question, str) or not question.strip():
        return f"{where}.question", "required, a non-empty string"
    options = inline_options(question)
    if not options:
        return f"{where}.question", "names no options ('Options: A: ..., B: ...')"
    category = row.get("question_type")
    if not isinstance(category, str) or not category.strip():
        return f"{where}.question_type", "required, a non-empty string"
    answer = row.get("answer")
    if not isinstance(answer, str) or not answer.strip():
        return f"{where}.answer", f"required, an option letter (got {answer!r:.60})"
    try:
        choice = ChoiceQuestion(question.strip(), options, answer.strip().upper(), category=category.strip(), profile=PROFILE)
    except ValueError as exc:
        return f"{where}.answer", str(exc)
    images = row.get("images")
    if not isinstance(images, list) or not images:
        return f"{where}.images", "required, a non-empty list of images"
    if len(images) > MAX_IMAGES:
        return f"{where}.images", f"{len(images)} images; a question shows at most {MAX_IMAGES}"
    names = []
    for index, image in enumerate(images):
        try:
            names.append(_embedded_image(image, cache))
        except ValueError as exc:
            return f"{where}.images[{index}]", str(exc)
    return Item(record_id, choice, tuple(names), embedded=True)


def _embedded_image(image: Any, cache: Path) -> str:
    """Write one embedded image into ``cache`` and give its file name; :class:`ValueError` says
    why it cannot be (the file is then checked like any image: :mod:`.external`)."""
    data = image.get("bytes") if isinstance(image, dict) else image
    if not isinstance(data, bytes) or not data:
        raise ValueError(f"must be an encoded image's bytes (got {type(data).__name__})")
    if len(data) > MAX_IMAGE_FILE_BYTES:
        raise ValueError(f"{len(data)} bytes, over the {MAX_IMAGE_FILE_BYTES} an image may have")
    return cached_image(data, cache, "neither a PNG nor a JPEG")

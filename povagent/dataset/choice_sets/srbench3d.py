"""3DSRBench (``ccvl/3DSRBench``, CC-BY-4.0) in its published TSV format.

A header line, then one record a line: ``index, qid, question, A, B, C, D, answer, category,
image`` (tab-separated, VLMEvalKit's layout). Options ``C`` and ``D`` may be empty or ``nan``
(a two-option question). ``image`` is a path relative to the TSV's folder, the image itself in
base64 (written once to the set's cache folder), or, as VLMEvalKit writes shared images, the
``index`` of an earlier record whose image it reuses. A cell ending in ``.png``, ``.jpg`` or
``.jpeg`` is a path; any other that is no earlier index is read as base64 (PNG or JPEG, else
refused), bounded by the line's bound. A qid names the question's copies:
``XXXXXXXX`` the question, ``-flip`` its flipped copy (the answer mirrored), ``-N`` its N-th
circular copy (the options rotated), ``-flip-N`` both. The copies of one question share
``ChoiceQuestion.group`` (the base qid); ``variant`` is the suffix (``""``, ``flip``, ``2``,
``flip-2``), from which :mod:`povagent_plugins.scorers.srbench3d` reads the set's Flip,
Circular and Flip+Circular accuracies.

This module reads the file and decodes embedded images (bounded by the line's bound); it
never opens an image file (see :mod:`.external`).
"""

from __future__ import annotations

import base64
import binascii
import csv
import hashlib
import re
from pathlib import Path

from povagent.answers.choice import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, record_id_problem, record_lines
from povagent.dataset.problems import Problem

#: The prompt profile the set is asked in (:mod:`povagent_plugins.strategies.set_profiles`).
PROFILE = "3dsrbench"
COLUMNS = ("index", "qid", "question", "A", "B", "C", "D", "answer", "category", "image")
_QID = re.compile(r"(?P<base>.+?)(?:-(?P<variant>flip(?:-\d+)?|\d+))?")
#: An image cell ending so is a path; any other is an earlier record's index or the image in base64.
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
_SIGNATURES = {b"\x89PNG\r\n\x1a\n": "png", b"\xff\xd8\xff": "jpg"}


def qid_parts(qid: str) -> tuple[str, str]:
    """``(question, copy)``: ``"VIN6MS3J-flip-1"`` -> ``("VIN6MS3J", "flip-1")``."""
    match = _QID.fullmatch(qid)
    assert match is not None  # the pattern matches any non-empty text
    return match.group("base"), match.group("variant") or ""


def read_srbench3d(file: Path, cache: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound record of the TSV as an item (embedded images written into ``cache``), and
    one problem per bad record."""
    name = str(file)
    items: list[Item] = []
    problems: list[Problem] = []
    header: list[str] | None = None
    image_of_index: dict[str, tuple[str, bool]] = {}
    seen: set[str] = set()
    for number, line in record_lines(file, "3DSRBench file", problems):
        cells = next(csv.reader([line], delimiter="\t"))
        if header is None:
            missing = [c for c in COLUMNS if c not in cells]
            if missing:
                problems.append(Problem(name, "line 1", f"the header names no column {', '.join(missing)} (a 3DSRBench TSV has {', '.join(COLUMNS)})"))
                return [], problems
            header = cells
            continue
        where = f"line {number}"
        if len(cells) != len(header):
            problems.append(Problem(name, where, f"{len(cells)} cells for {len(header)} columns; record left out"))
            continue
        row = dict(zip(header, cells))
        item = _item(row, where, cache, image_of_index)
        if isinstance(item, tuple):
            problems.append(Problem(name, *item))
        elif item.id in seen:
            problems.append(Problem(name, f"{where}.qid", f"{item.id!r} is used by an earlier record; this one left out"))
        else:
            seen.add(item.id)
            image_of_index[row["index"]] = (item.images[0], item.embedded)
            items.append(item)
    return items, problems


def _option(cell: str) -> str | None:
    """An option's text, or ``None`` for an absent one (empty or ``nan``, as pandas writes it)."""
    text = cell.strip()
    return None if not text or text.lower() == "nan" else text


def _item(row: dict[str, str], where: str, cache: Path, image_of_index: dict[str, tuple[str, bool]]) -> Item | tuple[str, str]:
    """The record as an item, or ``(where, message)`` saying what is wrong with it."""
    qid = row["qid"].strip() or row["index"].strip()
    id_problem = record_id_problem(qid)
    if id_problem:
        return f"{where}.qid", id_problem
    options = tuple((label, text) for label in "ABCD" if (text := _option(row[label])) is not None)
    if len(options) < 2:
        return f"{where}.A", "a question needs at least options A and B"
    group, variant = qid_parts(qid)
    try:
        question = ChoiceQuestion(row["question"].strip(), options, row["answer"].strip(), category=row["category"].strip(),
                                  group=group, variant=variant, profile=PROFILE)  # fmt: skip
    except ValueError as exc:
        return f"{where}.answer", str(exc)
    if not question.question:
        return f"{where}.question", "required, a non-empty string"
    image = row["image"].strip()
    if image in image_of_index:  # VLMEvalKit's shared image: the index of the record holding it
        rel, embedded = image_of_index[image]
        return Item(qid, question, (rel,), embedded)
    if not image:
        return f"{where}.image", "required: a path, the image in base64, or an earlier record's index"
    if image.lower().endswith(_IMAGE_SUFFIXES):
        return Item(qid, question, (image,))
    try:
        return Item(qid, question, (_embedded_image(image, cache),), embedded=True)
    except ValueError as exc:
        return f"{where}.image", str(exc)


def _embedded_image(text: str, cache: Path) -> str:
    """Decode a base64 image into ``cache`` and give its file name; :class:`ValueError` says
    why it cannot be (the file is then checked like any image: :mod:`.external`)."""
    try:
        data = base64.b64decode("".join(text.split()), validate=True)
    except binascii.Error as exc:
        raise ValueError(f"the image is not valid base64 ({exc})") from None
    kind = next((ext for sig, ext in _SIGNATURES.items() if data.startswith(sig)), None)
    if kind is None:
        raise ValueError("the decoded image is neither PNG nor JPEG")
    cache.mkdir(parents=True, exist_ok=True)
    # named by content, never by the qid (text from the file): the same image is one file
    name = f"{hashlib.sha256(data).hexdigest()[:32]}.{kind}"
    if not (cache / name).is_file():
        (cache / name).write_bytes(data)
    return name

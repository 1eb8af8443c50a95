"""3DSRBench (``ccvl/3DSRBench``, CC-BY-4.0) in its published TSV format.

A header line, then one record a line: ``index, qid, question, A, B, C, D, answer, category,
image`` (tab-separated, VLMEvalKit's layout). Options ``C`` and ``D`` may be empty or ``nan``
(a two-option question). ``image`` is a path relative to the TSV's folder, the image itself in
base64 (written once to the set's cache folder), or, as VLMEvalKit writes shared images, the
``index`` of the record whose image it reuses, before or after it (VLMEvalKit reads any image
cell of 64 characters or fewer as such an index). A cell ending in ``.png``, ``.jpg`` or
``.jpeg`` is a path; a cell of more than 64 characters is base64 (PNG or JPEG, else refused).
A cell may hold :data:`MAX_CELL_CHARS` characters (the real set's embedded images are a few
hundred KB of base64; Python's ``csv`` module stops at 128 KiB, so the line is split here,
with no global limit changed): a longer one is one problem naming the line and the column.
A qid names the question's copies: ``XXXXXXXX`` the question, ``-flip`` its flipped copy (the
answer mirrored), ``-N`` its N-th circular copy (the options rotated), ``-flip-N`` both. The
copies of one question share ``ChoiceQuestion.group`` (the base qid); ``variant`` is the suffix
(``""``, ``flip``, ``2``, ``flip-2``), from which :mod:`povagent_plugins.scorers.srbench3d_scorer`
reads the set's Flip, Circular and Flip+Circular accuracies. The ``category`` column holds one
of 12 sub-categories, each of one of 4 types (:data:`TYPES`, ``ChoiceQuestion.main_category``).

This module reads the file and decodes embedded images (bounded by the line's bound); it
never opens an image file (see :mod:`.external`).
"""

from __future__ import annotations

import base64
import binascii
import re
from pathlib import Path

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, cached_image, record_id_problem, record_lines
from povagent.dataset.problems import Problem

#: The prompt profile the set is asked in (:mod:`povagent_plugins.strategies.set_profiles`).
PROFILE = "3dsrbench"
COLUMNS = ("index", "qid", "question", "A", "B", "C", "D", "answer", "category", "image")
#: The set's four types and the twelve sub-categories (the ``category`` column) each holds, as the
#: authors' results script and lmms-eval's ``3dsrbench`` task map them: a question counts in its
#: sub-category's slice and in its type's (``ChoiceQuestion.main_category``).
TYPES = {
    "height": ("height_higher",),
    "location": ("location_above", "location_closer_to_camera", "location_next_to"),
    "orientation": ("orientation_in_front_of", "orientation_on_the_left", "orientation_viewpoint"),
    "multi_object": (
        "multi_object_closer_to",
        "multi_object_facing",
        "multi_object_viewpoint_towards_object",
        "multi_object_parallel",
        "multi_object_same_direction",
    ),
}
_TYPE_OF = {sub: kind for kind, subs in TYPES.items() for sub in subs}
_QID = re.compile(r"(?P<base>.+?)(?:-(?P<variant>flip(?:-\d+)?|\d+))?")
#: An image cell ending so is a path; any other is a record's index or the image in base64.
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
#: The most characters a cell may hold: 32 MiB, base64 of a 24 MiB image (the line's own
#: bound, :data:`~.external.MAX_RECORD_LINE_BYTES`, is twice that).
MAX_CELL_CHARS = 32 << 20
#: An image cell this short (and not a path) names the index of the record holding the image,
#: as VLMEvalKit reads it (``ImageBaseDataset``: ``len(cell) <= 64``).
INDEX_CELL_CHARS = 64


def tsv_cells(line: str) -> list[str]:
    """The tab-separated cells of one line as Python's ``csv`` excel-tab dialect reads them
    (a cell opening with ``"`` is quoted, ``""`` inside it a quote, text after its closing quote
    kept), without its field-size limit: the caller bounds each cell. One scan, linear time;
    :class:`ValueError` for a quote never closed."""
    if '"' not in line:
        return line.split("\t")
    cells: list[str] = []
    at, end = 0, len(line)
    while True:
        if at < end and line[at] == '"':
            parts, at = [], at + 1
            while True:
                close = line.find('"', at)
                if close == -1:
                    raise ValueError(f"a quoted cell (cell {len(cells) + 1}) is never closed")
                parts.append(line[at:close])
                if line.startswith('"', close + 1):  # a doubled quote stands for one
                    parts.append('"')
                    at = close + 2
                    continue
                at = close + 1
                break
            tab = line.find("\t", at)
            cells.append("".join(parts) + (line[at:] if tab == -1 else line[at:tab]))
        else:
            tab = line.find("\t", at)
            cells.append(line[at:] if tab == -1 else line[at:tab])
        if tab == -1:
            return cells
        at = tab + 1


def qid_parts(qid: str) -> tuple[str, str]:
    """``(question, copy)``: ``"VIN6MS3J-flip-1"`` -> ``("VIN6MS3J", "flip-1")``."""
    match = _QID.fullmatch(qid)
    assert match is not None  # the pattern matches any non-empty text
    return match.group("base"), match.group("variant") or ""


def read_srbench3d(file: Path, cache: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound record of the TSV as an item (embedded images written into ``cache``), and
    one problem per bad record. A record whose image cell names a later record's index is
    completed once that record is read (kept in file order)."""
    name = str(file)
    slots: list[Item | tuple[Item, str, str]] = []  # an item, or (item without image, index named, where)
    problems: list[Problem] = []
    header: list[str] | None = None
    image_of_index: dict[str, tuple[str, bool]] = {}
    seen: set[str] = set()
    for number, line in record_lines(file, "3DSRBench file", problems):
        where = f"line {number}"
        try:
            cells = tsv_cells(line)
        except ValueError as exc:
            problems.append(Problem(name, where, f"{exc}; record left out"))
            continue
        if header is None:
            missing = [c for c in COLUMNS if c not in cells]
            if missing:
                problems.append(Problem(name, "line 1", f"the header names no column {', '.join(missing)} (a 3DSRBench TSV has {', '.join(COLUMNS)})"))
                return [], problems
            header = cells
            continue
        if len(cells) != len(header):
            problems.append(Problem(name, where, f"{len(cells)} cells for {len(header)} columns; record left out"))
            continue
        if (over := next((k for k, c in enumerate(cells) if len(c) > MAX_CELL_CHARS), None)) is not None:
            problems.append(
                Problem(name, f"{where}.{header[over]}", f"a cell of {len(cells[over])} characters, over the {MAX_CELL_CHARS} a cell may hold; record left out")
            )
            continue
        row = dict(zip(header, cells))
        item = _item(row, where, cache)
        if isinstance(item, tuple):
            problems.append(Problem(name, *item))
        elif item.id in seen:
            problems.append(Problem(name, f"{where}.qid", f"{item.id!r} is used by an earlier record; this one left out"))
        else:
            seen.add(item.id)
            named = _named_index(row["image"].strip())
            if named is None:
                image_of_index.setdefault(row["index"].strip(), (item.images[0], item.embedded))
                slots.append(item)
            elif named in image_of_index:
                slots.append(_with_image(item, image_of_index[named]))
            else:
                slots.append((item, named, where))
    items: list[Item] = []
    for slot in slots:
        if isinstance(slot, Item):
            items.append(slot)
        elif slot[1] in image_of_index:
            items.append(_with_image(slot[0], image_of_index[slot[1]]))
        else:
            problems.append(
                Problem(
                    name,
                    f"{slot[2]}.image",
                    f"names the record of index {slot[1]!r}, and no record of that index holds an image (a path or base64); record left out",
                )
            )
    return items, problems


def _named_index(image: str) -> str | None:
    """The record index an image cell names (VLMEvalKit's shared image), or ``None`` for a path
    or an embedded image."""
    if len(image) > INDEX_CELL_CHARS or image.lower().endswith(_IMAGE_SUFFIXES):
        return None
    return image


def _with_image(item: Item, image: tuple[str, bool]) -> Item:
    """``item`` showing the image another record holds."""
    return Item(item.id, item.question, (image[0],), image[1])


def _option(cell: str) -> str | None:
    """An option's text, or ``None`` for an absent one (empty or ``nan``, as pandas writes it)."""
    text = cell.strip()
    return None if not text or text.lower() == "nan" else text


def _item(row: dict[str, str], where: str, cache: Path) -> Item | tuple[str, str]:
    """The record as an item, or ``(where, message)`` saying what is wrong with it; a record
    whose image cell names another record's index gets no image here (the caller gives it)."""
    qid = row["qid"].strip() or row["index"].strip()
    id_problem = record_id_problem(qid)
    if id_problem:
        return f"{where}.qid", id_problem
    options = tuple((label, text) for label in "ABCD" if (text := _option(row[label])) is not None)
    if len(options) < 2:
        return f"{where}.A", "a question needs at least options A and B"
    group, variant = qid_parts(qid)
    try:
        category = row["category"].strip()
        question = ChoiceQuestion(
            row["question"].strip(),
            options,
            row["answer"].strip(),
            category=category,
            group=group,
            variant=variant,
            profile=PROFILE,
            main_category=_TYPE_OF.get(category, ""),
        )
    except ValueError as exc:
        return f"{where}.answer", str(exc)
    if not question.question:
        return f"{where}.question", "required, a non-empty string"
    image = row["image"].strip()
    if not image:
        return f"{where}.image", "required: a path, the image in base64, or another record's index"
    if _named_index(image) is not None:
        return Item(qid, question, ())
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
    return cached_image(data, cache, "the decoded image is neither PNG nor JPEG")

"""ViewSpatial-Bench (``lidingm/ViewSpatial-Bench``, Apache-2.0) in its published format.

The set is one JSON list; each record is ``{question_type, image_path: [...], question, answer,
choices}``: ``choices`` is the options one a line (``"A. right\\nB. left"``), ``answer`` the
gold option written out (``"A. right"``), ``image_path`` one image, or 2-32 frames for the
scene-simulation questions, relative to the JSON file's folder. The gold label is read from
``answer`` by the set's official rule (ZJU-REAL ``eval/evaluate.py``, = lmms-eval
``viewspatial``): the first standalone ``A``-``D``, either case, upper-cased. The record's
position in the list is its id (the set gives none); ``question_type`` is its category.

This module reads the file; it never opens an image (see :mod:`.external`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, json_text_list, text_problems
from povagent.dataset.problems import Problem, all_text

#: The prompt profile the set is asked in (:mod:`povagent_plugins.strategies.set_profiles`).
PROFILE = "viewspatial"
#: The most frames a record shows (the scene-simulation questions show 2-32).
MAX_FRAMES = 32
#: The most options a record may list (one a line, each labelled A-Z).
MAX_OPTIONS = 26

_OPTION_LINE = re.compile(r"([A-Z])\.\s*(.*)")
_GOLD = re.compile(r"\b([A-D])\b", re.IGNORECASE)


def gold_label(answer: str) -> str | None:
    """The label the official rule reads in ``answer`` (``"A. right"`` -> ``A``), or ``None``."""
    match = _GOLD.search(answer)
    return match.group(1).upper() if match else None


def read_viewspatial(file: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound record of the JSON list as an item, and one problem per bad record."""
    name = str(file)
    data, unread, text_only = json_text_list(file, "ViewSpatial-Bench file")
    if data is None:
        return [], unread
    items: list[Item] = []
    problems: list[Problem] = []
    # the file's records hold only text (told from its text, or at once at C speed), or each is walked for it
    walk = not text_only and not all_text(data)
    options_of: dict[str, tuple[tuple[str, str], ...] | str] = {}
    golds: dict[str, str | None] = {}
    for index, record in enumerate(data):
        where = f"$[{index}]"
        not_text = text_problems(name, where, record) if walk else None
        if not_text:  # the rule the release reader holds: a lone surrogate is not text
            problems.extend(not_text)
            continue
        item = _item(index, record, where, options_of, golds)
        if isinstance(item, Item):
            items.append(item)
        else:
            problems.append(Problem(name, item[0], item[1]))
    return items, problems


def _item(
    index: int, record: Any, where: str, options_of: dict[str, tuple[tuple[str, str], ...] | str] | None = None, golds: dict[str, str | None] | None = None
) -> Item | tuple[str, str]:
    """The record as an item, or ``(json path, message)`` saying what is wrong with it.
    ``options_of``: each ``choices`` text read so far, with its options or its problem (a set's
    records repeat a few dozen option lists); ``golds``: each ``answer`` text read so far, with
    its gold label (a set's answers repeat a few dozen texts)."""
    if not isinstance(record, dict):
        # named by its type, never re-encoded: a record nesting ~1000 deep would overflow the encoder
        return where, f"a record must be a JSON object (got {type(record).__name__})"
    for key in ("question", "answer", "choices", "question_type"):
        if not isinstance(record.get(key), str) or not record[key].strip():
            return f"{where}.{key}", "required, a non-empty string"
    images = record.get("image_path")
    if not isinstance(images, list) or not images or not all(isinstance(p, str) and p for p in images):
        return f"{where}.image_path", "required, a list of 1 to 32 image paths"
    if len(images) > MAX_FRAMES:
        return f"{where}.image_path", f"{len(images)} images; a record shows at most {MAX_FRAMES}"
    choices = record["choices"]
    options = options_of.get(choices) if options_of is not None else None
    if options is None:
        options = _options(choices)
        if options_of is not None and len(options_of) < 4096:
            options_of[choices] = options
    if isinstance(options, str):  # why the text holds no options
        return f"{where}.choices", options
    answer = record["answer"]
    if golds is None:
        gold = gold_label(answer)
    elif (gold := golds.get(answer, "")) == "":  # "": not read yet (a label is never empty)
        gold = gold_label(answer)
        if len(golds) < 4096:
            golds[answer] = gold
    if gold is None:
        return f"{where}.answer", f"{record['answer'][:60]!r} names no label A-D (the official rule reads the first standalone letter)"
    try:
        question = ChoiceQuestion(record["question"], options, gold, category=record["question_type"], profile=PROFILE)
    except ValueError as exc:
        return (f"{where}.answer" if "gold" in str(exc) else f"{where}.choices"), str(exc)
    return Item(str(index), question, tuple(images))


def _options(choices: str) -> tuple[tuple[str, str], ...] | str:
    """The options of a record's ``choices`` text (``"A. right\\nB. left"``), or why it holds none."""
    lines = choices.strip().splitlines()
    if len(lines) > MAX_OPTIONS:  # each a label A-Z: more cannot be options, and the problem stays one short line
        return f"{len(lines)} lines; a question has at most {MAX_OPTIONS} options 'X. text'"
    options = []
    for number, line in enumerate(lines):
        match = _OPTION_LINE.fullmatch(line.strip())
        if match is None:
            return f"line {number + 1} {line[:60]!r} is not an option 'X. text'"
        options.append((match.group(1), match.group(2).strip()))
    return tuple(options)

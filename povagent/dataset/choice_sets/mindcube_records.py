"""MindCube (``MLL-Lab/MindCube``) in its published format.

One JSON record a line: ``{id, question, images: [...], gt_answer, ...}``, the raw files
(``data/raw/MindCube_tinybench.jsonl``, as the set's README and dataset card print a record) and
the converted ones (``data/prompts/general/*.jsonl``: the same keys plus ``input_prompt`` and
``grounded_output``) alike. ``question`` holds its options inline (``... A. Behind the sofa B.
Left of the lamp``) and either no ``<image>`` marker (the images go first, as MindCube's own
inference shows them) or one where each image goes (as many markers as images, lmms-eval's
copy of the set). ``gt_answer`` is the gold label. Images are paths relative to the folder
named (default: the JSONL file's; the set's own layout names them from ``data/``). The category
is the setting MindCube's evaluator reads in the id (``get_setting_from_id``: the first of
``around``, ``rotation``, ``translation``, ``among`` the lower-cased id contains; else
``other``). Other keys (``category``, ``meta_info``, ...) are left as they are.

This module reads the file; it never opens an image (see :mod:`.external`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, jsonl_records, record_id_problem, sound_items
from povagent.dataset.problems import Problem

#: The prompt profile the set is asked in (:mod:`povagent_plugins.strategies.set_profiles`).
PROFILE = "mindcube"
#: Where an image goes in a question.
IMAGE_MARKER = "<image>"

#: An inline option's label: a capital A-E, a full stop and a space, not inside a word.
_OPTION = re.compile(r"(?<![A-Za-z])([A-E])\.\s+")
#: The settings MindCube's evaluator looks for in an id, in its order.
SETTINGS = ("around", "rotation", "translation", "among")


def category_of(record_id: str) -> str:
    """The question's setting as MindCube's evaluator reads it (``get_setting_from_id`` @
    6d8fd9ac): the first of :data:`SETTINGS` the lower-cased id contains, else ``other``
    (``aroundnew_0012_q3`` -> ``around``)."""
    lowered = record_id.lower()
    return next((setting for setting in SETTINGS if setting in lowered), "other")


def inline_options(question: str) -> tuple[tuple[str, str], ...]:
    """The options written in ``question``: the last run of labels ``A.``, ``B.``, ... in order,
    each option's text running to the next label (empty: no such run).

    A run starts at the last ``A.`` with a ``B.`` somewhere after it and takes, after each
    label, the first next label that follows (other labels between are option text). One pass
    finds that ``A.`` and one more follows its run: time linear in the question's length (a
    question of many labels once took time quadratic in their number)."""
    marks = list(_OPTION.finditer(question))
    start, b_after = None, False
    for i in range(len(marks) - 1, -1, -1):
        label = marks[i].group(1)
        if label == "A" and b_after:
            start = i
            break
        b_after = b_after or label == "B"
    if start is None:
        return ()
    run = [marks[start]]
    for m in marks[start + 1 :]:
        if ord(m.group(1)) == ord(run[-1].group(1)) + 1:
            run.append(m)
    ends = [m.start() for m in run[1:]] + [len(question)]
    return tuple((m.group(1), question[m.end() : end].strip()) for m, end in zip(run, ends))


def read_mindcube(file: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound record of the JSONL file as an item, and one problem per bad record."""
    problems: list[Problem] = []
    items = sound_items(file, jsonl_records(file, "MindCube file", problems), _item, problems)
    return items, problems


def _item(record: Any, where: str) -> Item | tuple[str, str]:
    """The record as an item, or ``(where, message)`` saying what is wrong with it."""
    if not isinstance(record, dict):
        return where, "a record must be a JSON object"
    id_problem = record_id_problem(record.get("id"))
    if id_problem:
        return f"{where}.id", id_problem
    question = record.get("question")
    if not isinstance(question, str) or not question.strip():
        return f"{where}.question", "required, a non-empty string"
    images = record.get("images")
    if not isinstance(images, list) or not images or not all(isinstance(p, str) and p for p in images):
        return f"{where}.images", "required, a non-empty list of image paths"
    markers = question.count(IMAGE_MARKER)
    if markers and markers != len(images):
        return (
            f"{where}.question",
            f"holds {markers} {IMAGE_MARKER} marker(s) for {len(images)} image(s); give each image its marker, or none (the images then go first)",
        )
    options = inline_options(question.replace(IMAGE_MARKER, " "))
    if not options:
        return f"{where}.question", "names no options (inline 'A. ... B. ...')"
    gold = record.get("gt_answer")
    if not isinstance(gold, str):
        return f"{where}.gt_answer", f"required, an option label (got {gold!r:.60})"
    try:
        choice = ChoiceQuestion(question, options, gold, category=category_of(record["id"]), profile=PROFILE)
    except ValueError as exc:
        return f"{where}.gt_answer", str(exc)
    return Item(record["id"], choice, tuple(images))

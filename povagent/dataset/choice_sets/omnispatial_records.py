"""OmniSpatial (``qizekun/OmniSpatial``, CC-BY-NC-4.0) in its published format: ``data.json`` and its images.

``OmniSpatial-test.zip`` unpacks to ``data.json`` beside one folder per task type
(``Complex_Logic/``, ``Dynamic_Reasoning/``, ``Perspective_Taking/``, ``Spatial_Interaction/``).
``data.json`` is one JSON list; each record is ``{id, question, options: [...], answer,
task_type, sub_task_type}``: ``options`` the answer texts (labelled ``A``, ``B``, ... in order),
``answer`` the 0-based index of the gold one. The image is not named in the record: the set's
own evaluation (``api_eval.py``) opens ``<task_type>/<the id up to its first "_">.png`` under the
folder of ``data.json``, so questions ``15_0`` and ``15_1`` share ``15.png``; so does this reader
(the path confined to that folder like any image path).

The set counts a record in its task type and sub-task (:data:`TASKS`, as ``api_eval.py``'s
``blank_stats`` lists them: a record of another pair makes its worker fail, so it counts
nowhere); here such a record is a problem and left out. ``sub_task_type`` is the category and
``task_type`` the main category, so a report breaks Perspective_Taking down into Egocentric,
Allocentric and Hypothetical. The record id is ``<task_type>_<id>``, unique as the set's own
``uid`` is (an ``id`` may repeat across task types).

This module reads the file; it never opens an image (see :mod:`.external`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item, json_list, record_id_problem, sound_items
from povagent.dataset.paths import shown
from povagent.dataset.problems import Problem

#: The prompt profile the set is asked in.
PROFILE = "omnispatial"
#: The set's task types and the sub-tasks each holds (``api_eval.py`` ``blank_stats``).
TASKS = {
    "Dynamic_Reasoning": ("Manipulation", "Motion_Analysis"),
    "Spatial_Interaction": ("Traffic_Analysis", "Localization", "Geospatial_Strategy"),
    "Complex_Logic": ("Pattern_Recognition", "Geometric_Reasoning"),
    "Perspective_Taking": ("Egocentric", "Allocentric", "Hypothetical"),
}
#: The most options a question may list (labelled A-Z).
MAX_OPTIONS = 26
#: Where ``data.json`` sits in the unpacked test split (``dataset.path`` may name the folder).
DATA_FILE = "data.json"


def image_path(record_id: str, task_type: str) -> str:
    """The image of a record, relative to the folder of ``data.json``, as ``api_eval.py`` opens it."""
    return f"{task_type}/{record_id.split('_')[0]}.png"


def read_omnispatial(file: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound record of ``data.json`` as an item, and one problem per bad record."""
    data, unread = json_list(file, "OmniSpatial data.json")
    if data is None:
        return [], unread
    records = ((f"$[{index}]", record) for index, record in enumerate(data))
    return sound_items(file, records, _item, unread, reused="(task type and id) is used by an earlier record"), unread


def _item(record: Any, where: str) -> Item | tuple[str, str]:
    """The record as an item, or ``(json path, message)`` saying what is wrong with it."""
    if not isinstance(record, dict):
        return where, f"a record must be a JSON object (got {type(record).__name__})"
    for key in ("id", "question", "task_type", "sub_task_type"):
        if not isinstance(record.get(key), str) or not record[key].strip():
            return f"{where}.{key}", "required, a non-empty string"
    task, sub = record["task_type"], record["sub_task_type"]
    if sub not in TASKS.get(task, ()):
        known = "; ".join(f"{t}: {', '.join(s)}" for t, s in TASKS.items())
        return f"{where}.sub_task_type", f"{shown(task)} / {shown(sub)} is not one of the set's task types and sub-tasks ({known})"
    record_id = f"{task}_{record['id']}"
    id_problem = record_id_problem(record_id)
    if id_problem:
        return f"{where}.id", id_problem
    options = record.get("options")
    if not isinstance(options, list) or not 2 <= len(options) <= MAX_OPTIONS or not all(isinstance(o, str) for o in options):
        return f"{where}.options", f"required, a list of 2 to {MAX_OPTIONS} option texts"
    answer = record.get("answer")
    if not isinstance(answer, int) or isinstance(answer, bool) or not 0 <= answer < len(options):
        return f"{where}.answer", f"required, the 0-based index of the gold option among {len(options)} (got {answer!r:.60})"
    labelled = tuple((chr(65 + k), text) for k, text in enumerate(options))
    question = ChoiceQuestion(record["question"], labelled, chr(65 + answer), category=sub, main_category=task, profile=PROFILE)
    return Item(record_id, question, (image_path(record["id"], task),))

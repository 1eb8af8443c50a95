"""A lone surrogate is not text a dataset may hold.

JSON may write ``"\\ud800"``, and Python's ``json`` reads it as a string that no UTF-8 file can
hold: a run crashed writing its row (on every resume), ``show-prompt`` and every training export
crashed writing it, while ``validate`` said the set was valid. A file holding one is now refused
at the one place a dataset's JSON is read (:mod:`povagent.dataset.json_files`): ``validate``
names each such string by file and JSON path, and loading leaves the file's house out with the
same sentence. A house folder whose name is not UTF-8 (read as lone surrogates) is refused too.
"""

from __future__ import annotations

import json
import os
import shutil

from povagent.dataset.loader import load_dataset
from povagent.dataset.validate import validate_dataset

HOUSE = "train_house_00000"  # one pair (0) with four directions, three exploration frames
OTHER = "train_house_00001"
LONE = "\ud800"


def plant_in_sentence(editor) -> str:
    """A lone surrogate in pair 0's Inferred sentence for ``left``; returns its JSON path."""
    editor.edit(HOUSE, lambda d: d[0]["stage5"]["left"].update(type_a=f"the book {LONE} left of the bed"))
    return "$[0].stage5.left.type_a"


def test_validate_names_a_lone_surrogate_in_a_sentence_by_file_and_field(dataset_copy, editor):
    path = plant_in_sentence(editor)
    found = [p for p in validate_dataset(dataset_copy) if p.file == f"artifacts/{HOUSE}/{HOUSE}.json" and p.json_path == path]
    assert len(found) == 1 and "lone surrogate" in found[0].message and "\\ud800 at character 9" in found[0].message
    str(found[0]).encode("utf-8")  # the problem itself can be printed and written


def test_loading_leaves_the_house_out_naming_the_field_and_keeps_the_other(dataset_copy, editor):
    path = plant_in_sentence(editor)
    ds = load_dataset(dataset_copy)
    assert HOUSE not in ds.houses and OTHER in ds.houses
    assert [str(p) for p in ds.problems if p.json_path == path and "lone surrogate" in p.message]
    for inst in ds.instances():  # nothing loaded holds what a results file cannot
        inst.sentence.encode("utf-8")


def test_a_lone_surrogate_in_a_key_is_named_with_the_key_escaped(dataset_copy, editor):
    editor.edit(HOUSE, lambda d: d[0]["camera"].update({f"note{LONE}": 1}))
    found = [p for p in validate_dataset(dataset_copy) if "lone surrogate" in p.message]
    assert [(p.json_path, p.message.split(" ")[0]) for p in found] == [("$[0].camera.note\\ud800", "key")]


def test_a_lone_surrogate_in_the_visible_objects_or_meta_is_refused_too(dataset_copy, editor):
    editor.edit(HOUSE, lambda d: d["exploration_images/frame_000.png"].append(f"Bed{LONE}"), "per_image_visible_objects.json")
    (dataset_copy / "meta.json").write_text(json.dumps({"version": f"1{LONE}"}))
    found = {(p.file, p.json_path) for p in validate_dataset(dataset_copy) if "lone surrogate" in p.message}
    assert found == {(f"artifacts/{HOUSE}/per_image_visible_objects.json", "$.exploration_images/frame_000.png[1]"), ("meta.json", "$.version")}
    assert {(p.file, p.json_path) for p in load_dataset(dataset_copy).problems if "lone surrogate" in p.message} == found


def test_an_escaped_surrogate_pair_is_one_character_and_loads(dataset_copy, editor):
    editor.edit(HOUSE, lambda d: d[0]["stage5"]["left"].update(type_a="the book \U0001f4d6 left of the bed"))
    assert "\\ud83d\\udcd6" in editor.path(HOUSE).read_text()  # JSON's escaped pair of an open book emoji
    assert validate_dataset(dataset_copy) == []
    assert "\U0001f4d6" in load_dataset(dataset_copy).instance(f"{HOUSE}/0/left/a").sentence


def test_a_house_folder_whose_name_is_not_utf8_is_refused_naming_it(dataset_copy):
    bad = os.fsdecode(b"train_house_\xff")  # the name as Python reads it: a lone surrogate
    shutil.move(dataset_copy / "artifacts" / HOUSE, dataset_copy / "artifacts" / bad)
    (dataset_copy / "artifacts" / bad / f"{HOUSE}.json").rename(dataset_copy / "artifacts" / bad / f"{bad}.json")
    expected = ["artifacts/train_house_\\udcff: the folder name is not UTF-8 text"]
    assert [str(p)[: len(expected[0])] for p in validate_dataset(dataset_copy)] == expected
    ds = load_dataset(dataset_copy)
    assert list(ds.houses) == [OTHER] and [str(p)[: len(expected[0])] for p in ds.problems] == expected

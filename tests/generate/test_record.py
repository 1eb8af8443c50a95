"""A house's record carries the digest of what made it (index, generator version, seed and
options), so a record changed since is told from the house it describes."""

from __future__ import annotations

import json

from povagent.generate.record import RECORD, generation_digest, parse_record, read_record, record_problem


def test_a_generated_house_records_the_digest_of_its_index_and_options(tiny_dataset):
    raw = json.loads((tiny_dataset.house_dir / RECORD).read_text())
    assert raw["digest"] == generation_digest(raw["index"], raw["options"])
    assert raw["options"]["seed"] == 7 and raw["options"]["version"] and raw["index"] == 0
    assert record_problem(read_record(tiny_dataset.house_dir), tiny_dataset.house_dir.name) is None


def test_every_option_and_the_index_change_the_digest(tiny_dataset):
    raw = json.loads((tiny_dataset.house_dir / RECORD).read_text())
    digest = generation_digest(raw["index"], raw["options"])
    changed = {generation_digest(raw["index"] + 1, raw["options"])}
    for name, value in {"seed": 8, "version": "0", "frames": 7, "with_render": False, "judge": "x", "judge_options": {"a": 1}}.items():
        changed.add(generation_digest(raw["index"], {**raw["options"], name: value}))
    assert digest not in changed and len(changed) == 7


def test_a_record_whose_seed_was_changed_names_the_digest_field(tiny_dataset):
    raw = json.loads((tiny_dataset.house_dir / RECORD).read_text())
    raw["options"]["seed"] = 8
    field, why = record_problem(parse_record(raw), tiny_dataset.house_dir.name)
    assert field == "digest" and "changed after the house was generated" in why


def test_a_record_written_before_digests_holds_and_says_it_has_none(tiny_dataset):
    raw = json.loads((tiny_dataset.house_dir / RECORD).read_text())
    del raw["digest"]
    record = parse_record(raw)
    assert record is not None and record.digest is None and record_problem(record, tiny_dataset.house_dir.name) is None


def test_a_negative_seed_is_refused_even_with_a_matching_digest(tiny_dataset):
    raw = json.loads((tiny_dataset.house_dir / RECORD).read_text())
    raw["options"]["seed"] = -1
    raw["digest"] = generation_digest(raw["index"], raw["options"])
    assert record_problem(parse_record(raw), tiny_dataset.house_dir.name)[0] == "options.seed"


def test_a_record_naming_another_house_is_refused_by_its_index(tiny_dataset):
    record = read_record(tiny_dataset.house_dir)
    assert record_problem(record, "train_house_00003")[0] == "index"


def test_a_pipe_planted_as_the_record_reads_as_no_record_at_once(tmp_path):
    import os

    os.mkfifo(tmp_path / RECORD)  # no writer: an ordinary open waits forever
    assert read_record(tmp_path) is None

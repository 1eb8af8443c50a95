"""The simulated speaker answers from the pair's facts only, by template."""

from __future__ import annotations

import json

import pytest

from povagent.active.speaker import CANNOT_SAY, pair_facts
from povagent.errors import DatasetError


def test_asked_what_they_were_doing_the_speaker_gives_the_stated_sentence(facts):
    said = facts.answer("What were you doing?")
    assert "sofa" in said and facts.stated in said


def test_asked_what_they_faced_the_speaker_names_the_anchor(facts):
    assert facts.answer("Which way were you facing?") == "I was facing the floor lamp."


@pytest.mark.parametrize("question", ["Is the mug near it?", "What colour is it?", ""])
def test_anything_else_gets_i_cant_say_more(facts, question):
    assert facts.answer(question) == CANNOT_SAY


def test_facts_are_read_from_the_house_pair_file(active_dataset):
    folder = active_dataset / "artifacts" / "train_house_00000"
    pair = json.loads((folder / "train_house_00000.json").read_text())[0]
    direction = sorted(pair["stage5"])[0]
    facts = pair_facts(folder, "train_house_00000", pair["pair_id"], direction)
    assert facts.stated == pair["stage5"][direction]["type_b"]
    assert facts.anchor_type == pair["object_landmark"]["raw_metadata"]["objectType"]


def test_an_unknown_pair_is_one_line_naming_the_file(active_dataset):
    folder = active_dataset / "artifacts" / "train_house_00000"
    with pytest.raises(DatasetError, match=r"train_house_00000\.json: no pair nope"):
        pair_facts(folder, "train_house_00000", "nope", "front")


def the_pair(active_dataset):
    folder = active_dataset / "artifacts" / "train_house_00000"
    pair = json.loads((folder / "train_house_00000.json").read_text())[0]
    return folder, pair, sorted(pair["stage5"])[0]


def test_by_default_the_speaker_tells_inferred_the_stated_sentence_and_the_furniture(active_dataset):
    folder, pair, direction = the_pair(active_dataset)
    said = pair_facts(folder, "train_house_00000", pair["pair_id"], direction, "a").answer("What were you doing?")
    assert pair["stage5"][direction]["type_b"] in said and said.startswith("I was at the ")


def test_kept_to_inferred_the_speaker_says_what_they_were_doing_not_where(active_dataset):
    folder, pair, direction = the_pair(active_dataset)
    facts = pair_facts(folder, "train_house_00000", pair["pair_id"], direction, "a", knowledge="condition")
    said = facts.answer("What were you doing, and where were you sitting?")
    assert said == f'As I put it: "{pair["stage5"][direction]["type_a"]}"'
    assert pair["stage5"][direction]["type_b"] not in said


def test_kept_to_stated_the_speaker_tells_what_the_stated_sentence_says(active_dataset):
    folder, pair, direction = the_pair(active_dataset)
    args = (folder, "train_house_00000", pair["pair_id"], direction, "b")
    assert pair_facts(*args, knowledge="condition") == pair_facts(*args, knowledge="stated")


def test_kept_to_given_the_speaker_quotes_the_given_sentence_only(active_dataset):
    folder, pair, direction = the_pair(active_dataset)
    facts = pair_facts(folder, "train_house_00000", pair["pair_id"], direction, "c", knowledge="condition")
    assert facts.answer("What were you doing?") == f'As I put it: "{pair["stage6"][direction]["type_c"]}"'


def test_kept_to_a_condition_the_speaker_still_names_what_they_faced(active_dataset):
    folder, pair, direction = the_pair(active_dataset)
    facts = pair_facts(folder, "train_house_00000", pair["pair_id"], direction, "a", knowledge="condition")
    assert facts.answer("Which way were you facing?").startswith("I was facing the ")


def test_a_pair_without_the_conditions_sentence_is_one_line_naming_the_field(active_dataset, tmp_path):
    _folder, pair, direction = the_pair(active_dataset)
    del pair["stage5"][direction]["type_a"]
    (tmp_path / "train_house_00000.json").write_text(json.dumps([pair]))
    with pytest.raises(DatasetError, match=rf"pair {pair['pair_id']}: field stage5\.{direction}\.type_a is missing"):
        pair_facts(tmp_path, "train_house_00000", pair["pair_id"], direction, "a", knowledge="condition")


def test_a_pipe_planted_as_the_pair_file_is_one_line_never_waited_on(tmp_path):
    import os

    os.mkfifo(tmp_path / "train_house_00000.json")  # no writer: an ordinary open waits forever
    with pytest.raises(DatasetError, match="not a regular file") as refused:
        pair_facts(tmp_path, "train_house_00000", "pair_000", "front")
    assert "\n" not in str(refused.value)

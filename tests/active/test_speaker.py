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

"""The active strategy's ``speaker`` option: what ``ask`` may tell reaches the episode, a bad
value is refused in one line, and the option is part of the config hash."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.dataset.loader import load_dataset
from povagent.errors import PluginError
from povagent.exchange.images import ImageStore
from povagent.plugins import get_plugin_host
from povagent_plugins.strategies.active import ActiveStrategy

QUESTION = "What were you doing, and where?"


@pytest.fixture(scope="module")
def inferred(generated_release):
    dataset = load_dataset(generated_release)
    return next(i for i in dataset.instances(conditions=["a"]) if i.house_id == "train_house_00000")


def test_speaker_condition_keeps_an_inferred_episode_to_the_inferred_sentence(inferred):
    episode = ActiveStrategy(speaker="condition").episode(inferred, ImageStore())
    assert episode.speaker.answer(QUESTION) == f'As I put it: "{inferred.sentence}"'


def test_the_default_speaker_tells_an_inferred_episode_the_stated_sentence(inferred):
    said = ActiveStrategy().episode(inferred, ImageStore()).speaker.answer(QUESTION)
    assert said.startswith("I was at the ") and inferred.sentence not in said


def pipeline(tmp_path, **options):
    doc = {"dataset": "x", "backend": "explorer-random", "strategy": {"name": "active", "options": options},
           "parser": "active", "output": str(tmp_path / "run")}  # fmt: skip
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(doc))
    return load_pipeline(tmp_path / "p.yaml")


def test_the_speaker_option_is_in_the_config_hash(tmp_path):
    assert pipeline(tmp_path, speaker="condition").config_hash() != pipeline(tmp_path, speaker="stated").config_hash()


def test_an_unknown_speaker_is_refused_in_one_line_when_the_strategy_is_made():
    with pytest.raises(PluginError, match="speaker must be one of stated, condition, got 'everything'") as caught:
        get_plugin_host().strategy("active", {"speaker": "everything"})
    assert "\n" not in str(caught.value)

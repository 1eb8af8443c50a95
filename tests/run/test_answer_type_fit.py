"""A run whose strategy asks for an answer type its instances do not ask for is refused at load,
in one line naming the strategy, the instance and both types, before any request: a set of
point instances asked for choices would otherwise score every row as a parse error, silently."""

from __future__ import annotations

import pytest
import yaml

from povagent.answers.types import AnswerType, answer_type_misfit
from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent.run.progress import QuietProgress
from povagent.run.runner import run_pipeline
from povagent.testing.pytest_plugin import write_release
from povagent_plugins.answers.choice_answer import CHOICE
from povagent_plugins.answers.point import POINT


def test_a_strategy_asking_another_answer_type_than_the_instances_is_refused_in_one_line(tmp_path):
    release = write_release(tmp_path / "povbench", houses=1, pairs=1, pair_directions=1, frames=2)
    path = tmp_path / "choice.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(release)}, "backend": {"name": "center"}, "strategy": "choice",
        "parser": "choice", "scorers": [], "output": str(tmp_path / "run"),
    }))  # fmt: skip
    with pytest.raises(ConfigError) as refused:
        run_pipeline(load_pipeline(path), progress=QuietProgress())
    (line,) = str(refused.value).splitlines()
    assert "strategy 'choice' asks for a 'choice' answer" in line and "asks for a 'point' answer" in line
    assert not (tmp_path / "run" / "results.jsonl").exists()


def test_a_type_refining_the_asked_one_answers_its_instances(mini_root):
    from povagent.dataset.loader import load_dataset

    instances = list(load_dataset(mini_root, check_images=False).instances())
    refined = AnswerType(name="anchor-point", description="", value_schema={}, value_of=POINT.value_of, gold=POINT.gold,
                         show=POINT.show, refines="point")  # fmt: skip
    assert answer_type_misfit("basic", POINT, instances) is None
    assert answer_type_misfit("anchor", refined, instances) is None
    assert answer_type_misfit("choice", CHOICE, instances) is not None

"""An answer-mode YAML: a pipeline with `backend: human`, `annotator:`, and the annotator's order."""

from __future__ import annotations

import pytest
import yaml

from povagent.annotate.study_config import load_answer_study
from povagent.config.models import MAX_WAIT_S
from povagent.errors import ConfigError


def write(tmp_path, mini_root, **data):
    base = {"dataset": {"path": str(mini_root)}, "backend": "human", "annotator": "alice", "output": str(tmp_path / "run")}
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump({**base, **data}))
    return path


def test_the_annotator_becomes_the_human_backends_option_and_one_question_is_asked_at_a_time(tmp_path, mini_root):
    study = load_answer_study(write(tmp_path, mini_root, concurrency=8, timeout=5))
    assert study.pipeline.backend.options == {"annotator": "alice"}
    assert study.pipeline.concurrency == 1 and study.pipeline.timeout == MAX_WAIT_S
    assert study.pipeline.cache.enabled is False


def test_another_backend_is_refused_naming_the_field(tmp_path, mini_root):
    with pytest.raises(ConfigError, match=r"study.yaml.*backend: answer mode takes `backend: human`"):
        load_answer_study(write(tmp_path, mini_root, backend="center"))


def test_a_missing_annotator_is_refused_naming_the_field(tmp_path, mini_root):
    path = write(tmp_path, mini_root)
    data = yaml.safe_load(path.read_text())
    del data["annotator"]
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match="annotator: name the person"):
        load_answer_study(path)


def test_the_order_options_are_read(tmp_path, mini_root):
    study = load_answer_study(write(tmp_path, mini_root, annotation={"seed": 4, "pairs_apart": False}))
    assert (study.seed, study.pairs_apart) == (4, False)


def test_an_unknown_order_option_is_refused(tmp_path, mini_root):
    with pytest.raises(ConfigError, match="annotation: takes only seed"):
        load_answer_study(write(tmp_path, mini_root, annotation={"shuffle": True}))

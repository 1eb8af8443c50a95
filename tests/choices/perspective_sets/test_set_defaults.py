"""A choice set named with a model and nothing else is a complete pipeline: the set's answer
type chooses the strategy and the scorers (the set's own scorer first), the set its official
parser; whatever the pipeline names is kept."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline

#: Each set's official rule, as its registered format names it (what a pipeline naming no parser gets).
OFFICIAL_SET_PARSERS = {"viewspatial": "viewspatial-official", "mindcube": "mindcube-official", "3dsrbench": "vlmevalkit-exact"}


@pytest.fixture
def bare_pipeline(tmp_path, set_file, offline_plugin_file):
    """``bare_pipeline(format, **more) -> Path``: a pipeline naming only the set and the backend."""

    def make(format: str, **more) -> object:
        data = {"plugins": [str(offline_plugin_file)], "dataset": {"path": str(set_file(format)), "format": format},
                "backend": "oracle", "output": str(tmp_path / f"run-{format}"), **more}  # fmt: skip
        path = tmp_path / f"{format}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return make


@pytest.mark.parametrize("format", ["viewspatial", "mindcube", "3dsrbench"])
def test_a_set_and_a_backend_are_a_complete_pipeline(bare_pipeline, format):
    config = load_pipeline(bare_pipeline(format))
    assert config.strategy.name == "choice"
    assert config.parser is not None and config.parser.name == OFFICIAL_SET_PARSERS[format]
    result = run_pipeline(config)
    assert result.summary.metrics["choice"].overall["accuracy"].value == 1.0


def test_3dsrbench_gets_its_own_scorer_first(bare_pipeline):
    config = load_pipeline(bare_pipeline("3dsrbench"))
    assert [s.name for s in config.scorers] == ["choice-3dsrbench", "choice"]


def test_the_strategy_and_scorers_a_pipeline_names_are_kept(bare_pipeline):
    config = load_pipeline(bare_pipeline("3dsrbench", strategy={"name": "choice", "options": {"profile": "plain"}}, scorers=["choice"]))
    assert [s.name for s in config.scorers] == ["choice"] and config.strategy.options == {"profile": "plain"}


def test_a_povbench_pipeline_keeps_its_own_defaults(tmp_path, mini_root):
    path = tmp_path / "point.yaml"
    path.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center", "output": str(tmp_path / "run")}))
    config = load_pipeline(path)
    assert config.strategy.name == "basic" and [s.name for s in config.scorers] == ["official"]

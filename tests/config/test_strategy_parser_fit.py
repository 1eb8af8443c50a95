"""A strategy names the parser its answers need and the answer type it asks for: a pipeline
naming no parser gets that parser, one naming a parser that cannot read them is refused at load,
in one line naming the file and line, before any request."""

from __future__ import annotations

import textwrap

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError

CHOICE_PLUGIN = '''
from povagent import hookimpl
from povagent.answers.types import AnswerType
from povagent_plugins.strategies.basic import BasicStrategy

CHOICE = AnswerType("ranking", "a label", {"type": "object"}, lambda p: None, lambda i: None, lambda v: "")


class ChoiceStrategy(BasicStrategy):
    answer_type = "ranking"


@hookimpl
def register_strategies(register):
    register("test-choice", ChoiceStrategy, description="test: asks for a choice")
'''
#: The plugin above, and the choice answer type registered.
CHOICE_TYPE = '''
@hookimpl
def register_answer_types(register):
    register("ranking", CHOICE)
'''


def write(tmp_path, text: str):
    path = tmp_path / "pipeline.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def test_the_active_strategy_without_a_parser_gets_the_active_parser(tmp_path):
    config = load_pipeline(write(tmp_path, "dataset: d\nbackend: explorer-random\nstrategy: active\noutput: runs/a\n"))
    assert config.parser.name == "active"


def test_the_strategys_parser_wins_over_a_model_profiles_default(tmp_path):
    config = load_pipeline(write(tmp_path, "dataset: d\nmodel: qwen3-vl-8b\nstrategy: active\noutput: runs/a\n"))
    assert config.parser.name == "active"


def test_a_strategy_needing_no_parser_still_gets_official(tmp_path):
    config = load_pipeline(write(tmp_path, "dataset: d\nbackend: center\nstrategy: basic\noutput: runs/b\n"))
    assert config.parser.name == "official"


def test_a_parser_that_cannot_read_the_active_record_is_refused_in_one_line(tmp_path):
    path = write(tmp_path, "dataset: d\nbackend: explorer-random\nstrategy: active\nparser: json\noutput: runs/a\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert str(err.value) == (
        f"{path}, line 4: parser 'json' cannot read the answers of strategy 'active', which need parser 'active' "
        "(name it, or leave parser: out)"
    )


def test_a_strategy_asking_for_an_answer_type_no_plugin_registers_is_refused(tmp_path):
    (tmp_path / "choice_plugin.py").write_text(CHOICE_PLUGIN, encoding="utf-8")
    path = write(tmp_path, "plugins: [choice_plugin.py]\ndataset: d\nbackend: center\nstrategy: test-choice\noutput: runs/c\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert str(err.value) == (
        f"{path}, line 4: strategy 'test-choice' asks for a ranking answer, an answer type no loaded plugin registers (registered: choice, choice-or-number, "
        "number, point, walk)"
    )


def test_a_parser_not_reading_the_asked_answer_type_is_refused(tmp_path):
    (tmp_path / "choice_plugin.py").write_text(CHOICE_PLUGIN + CHOICE_TYPE, encoding="utf-8")
    path = write(tmp_path, "plugins: [choice_plugin.py]\ndataset: d\nbackend: center\nstrategy: test-choice\noutput: runs/c\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert str(err.value) == f"{path}, line 4: parser 'official' reads point answers, and strategy 'test-choice' asks for a ranking answer"

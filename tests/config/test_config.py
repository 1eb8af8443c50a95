"""Pipeline YAML: validation with file, line and nearest-name messages; defaults; hashing."""

from __future__ import annotations

import textwrap

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.config.yaml_reader import parse_yaml
from povagent.errors import ConfigError

GOOD = """\
dataset: {path: data/povbench}
backend: {name: center}
strategy: basic
parser: json
output: runs/x
"""


def write(tmp_path, text: str, name: str = "pipeline.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_valid_pipeline_gets_defaults(tmp_path):
    config = load_pipeline(write(tmp_path, GOOD))
    assert config.backend.name == "center" and config.strategy.name == "basic" and config.parser.name == "json"
    assert [s.name for s in config.scorers] == ["official"]
    assert config.run_indices == [0] and config.concurrency == 16 and config.retry.attempts == 5


def test_typo_in_top_level_key_names_file_line_and_nearest_key(tmp_path):
    path = write(tmp_path, GOOD + "stratgy: cot\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 6: unknown key 'stratgy' in the top level (did you mean 'strategy'?)" in str(err.value)


def test_typo_in_nested_key_names_its_section(tmp_path):
    path = write(tmp_path, GOOD + "retry:\n  attempts: 3\n  max_wiat: 5\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 8: unknown key 'max_wiat' in retry (did you mean 'max_wait'?)" in str(err.value)


def test_unknown_strategy_suggests_the_registered_name(tmp_path):
    path = write(tmp_path, GOOD.replace("strategy: basic", "strategy: spatial_cot"))
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 3: strategy: unknown strategy 'spatial_cot' (did you mean 'spatial-cot'?)" in str(err.value)


def test_unknown_backend_in_mapping_points_at_its_name_line(tmp_path):
    path = write(tmp_path, GOOD.replace("backend: {name: center}", "backend:\n  name: centre\n  options: {}"))
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 3: backend.name: unknown backend 'centre' (did you mean 'center'?)" in str(err.value)


def test_unknown_scorer_in_list_points_at_the_item(tmp_path):
    path = write(tmp_path, GOOD + "scorers:\n  - official\n  - oficial\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 8: scorers[1]: unknown scorer 'oficial' (did you mean 'official'?)" in str(err.value)


def test_bad_condition_lists_the_valid_ones(tmp_path):
    path = write(tmp_path, GOOD + "instances: {conditions: [a, d]}\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 6: instances.conditions[1]:" in str(err.value) and "'a', 'b' or 'c'" in str(err.value)


def test_condition_names_are_accepted(tmp_path):
    config = load_pipeline(write(tmp_path, GOOD + "instances: {conditions: [Inferred, given]}\n"))
    assert [c.value for c in config.instances.conditions] == ["a", "c"]


def test_missing_output_is_reported(tmp_path):
    path = write(tmp_path, GOOD.replace("output: runs/x\n", ""))
    with pytest.raises(ConfigError, match=r"output: required key is missing"):
        load_pipeline(path)


def test_backend_or_model_is_required(tmp_path):
    path = write(tmp_path, GOOD.replace("backend: {name: center}\n", ""))
    with pytest.raises(ConfigError, match=r"a backend is required"):
        load_pipeline(path)


def test_invalid_yaml_names_the_line(tmp_path):
    path = write(tmp_path, GOOD + "runs: [1, 2\n")
    with pytest.raises(ConfigError, match=rf"{path}, line \d+: not valid YAML"):
        load_pipeline(path)


def test_python_tags_are_refused_not_executed(tmp_path):
    path = write(tmp_path, GOOD + "runs: !!python/object/apply:os.system ['echo pwned']\n")
    with pytest.raises(ConfigError, match=r"not valid YAML"):
        load_pipeline(path)


def test_missing_file_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError, match=r"file not found"):
        load_pipeline(tmp_path / "nope.yaml")


def test_model_profile_shorthand_picks_litellm_and_the_profile_parser(tmp_path):
    from povagent.plugins import get_plugin_host

    profile = get_plugin_host().profile("qwen3-vl-8b")
    config = load_pipeline(write(tmp_path, "dataset: d\nmodel: qwen3-vl-8b\noutput: runs/q\n"))
    assert config.backend.name == "litellm" and config.backend.options == {"model": "qwen3-vl-8b"}
    assert config.parser.name == profile.default_parser


def test_model_and_backend_together_are_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"either model: .* or backend:"):
        load_pipeline(write(tmp_path, GOOD + "model: gpt-5.4\n"))


def test_config_hash_ignores_how_it_runs_but_not_what_it_asks(tmp_path):
    base = load_pipeline(write(tmp_path, GOOD))
    faster = load_pipeline(write(tmp_path, GOOD.replace("runs/x", "runs/y") + "concurrency: 64\n", "b.yaml"))
    other = load_pipeline(write(tmp_path, GOOD.replace("strategy: basic", "strategy: cot"), "c.yaml"))
    assert base.config_hash() == faster.config_hash()
    assert base.config_hash() != other.config_hash()


def test_yaml_lines_are_recorded_for_keys_and_items():
    source = parse_yaml("a: 1\nb:\n  - x\n  - y\nc: {d: 2}\n", "f.yaml")
    assert source.lines[("a",)] == 1 and source.lines[("b", 1)] == 4 and source.lines[("c", "d")] == 5
    assert source.where(("c", "d", "deeper")) == "f.yaml, line 5"

"""Checks on the options a pipeline gives its plugins: numbers are finite, read at load."""

from __future__ import annotations

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError

BASE = """\
dataset: {path: data/povbench}
backend: {name: center}
output: runs/x
"""


@pytest.mark.parametrize("spelling", [".nan", ".NaN", ".inf", "-.inf"])
def test_a_non_finite_temperature_is_refused_at_load_naming_the_line(tmp_path, spelling):
    path = tmp_path / "pipeline.yaml"
    path.write_text(BASE + f"strategy:\n  name: basic\n  options:\n    temperature: {spelling}\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    message = str(err.value).splitlines()[-1]
    assert message.startswith(f"{path}, line 7: strategy.options.temperature: ") and "not a finite number" in message


def test_a_non_finite_number_deep_in_backend_options_is_refused(tmp_path):
    path = tmp_path / "pipeline.yaml"
    path.write_text(BASE.replace("backend: {name: center}", "backend: {name: center, options: {extra: {limits: [1, .inf]}}}"))
    with pytest.raises(ConfigError, match=r"line 2: backend\.options\.extra\.limits\[1\]: inf is not a finite number"):
        load_pipeline(path)


def test_finite_numbers_in_options_load(tmp_path):
    path = tmp_path / "pipeline.yaml"
    path.write_text(BASE + "strategy:\n  name: basic\n  options:\n    temperature: 0.7\n    max_tokens: 256\n")
    assert load_pipeline(path).strategy.options == {"temperature": 0.7, "max_tokens": 256}

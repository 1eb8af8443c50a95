"""A model-profile typo gets the same "did you mean" wherever the profile is named.

``model: qwen3-vl8b`` was caught with a suggestion; the same typo as the litellm backend's
``options.model`` went to litellm as a model string and every row failed. A bare name (no
``provider/``) that is not a profile but is a near miss of one is now refused the same way,
before any request; a real litellm model string, or a bare name far from every profile, is
left to litellm.
"""

from __future__ import annotations

import textwrap

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

HEAD = """\
dataset: {path: data/povbench}
output: runs/x
"""


def write(tmp_path, text):
    path = tmp_path / "pipeline.yaml"
    path.write_text(HEAD + textwrap.dedent(text))
    return path


def suggestion(message: str) -> str:
    return message[message.index("unknown profile") :]


def test_the_typo_under_model_and_under_backend_options_gets_the_same_suggestion(tmp_path):
    with pytest.raises(ConfigError) as under_model:
        load_pipeline(write(tmp_path, "model: qwen3-vl8b\n"))
    with pytest.raises(ConfigError) as under_options:
        load_pipeline(write(tmp_path, "backend:\n  name: litellm\n  options:\n    model: qwen3-vl8b\n    api_base: http://127.0.0.1:8000/v1\n"))
    assert "(did you mean 'qwen3-vl-8b'?)" in str(under_options.value)
    assert suggestion(str(under_options.value)) == suggestion(str(under_model.value))


def test_the_message_names_the_file_line_and_field(tmp_path):
    path = write(tmp_path, "backend:\n  name: litellm\n  options:\n    model: gemini-robotic-er\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 6: backend.options.model: unknown profile 'gemini-robotic-er' (did you mean 'gemini-robotics-er'?)" in str(err.value)


def test_the_backend_itself_refuses_the_typo_for_code_that_skips_the_config():
    with pytest.raises(ConfigError, match=r"did you mean 'qwen3-vl-8b'"):
        LiteLLMBackend(model="qwen3-vl8b", api_base="http://127.0.0.1:8000/v1")


@pytest.mark.parametrize("model", ["openai/gpt-4o", "gpt-4o", "gpt-5", "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct", "qwen3-vl-8b"])
def test_litellm_model_strings_and_real_profiles_are_accepted(tmp_path, model):
    text = f"backend:\n  name: litellm\n  options:\n    model: {model}\n    api_base: http://127.0.0.1:8000/v1\n"
    assert load_pipeline(write(tmp_path, text)).backend.options["model"] == model
    LiteLLMBackend(model=model, api_base="http://127.0.0.1:8000/v1")

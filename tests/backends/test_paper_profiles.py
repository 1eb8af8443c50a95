"""The paper's model profiles (plugins/backends/profiles.py)."""

from __future__ import annotations

import pytest

from povagent.dataset.models import Condition
from povagent.plugins import get_plugin_host
from povagent_plugins.backends.profiles import PAPER_PROFILES

PAPER_MODELS = {
    "gpt-5.4": "openai/gpt-5.4",
    "gemini-2.5-flash": "gemini/gemini-2.5-flash",
    "gemini-robotics-er": "gemini/gemini-robotics-er-1.6-preview",
    "gemma-4": "gemini/gemma-4-26b-a4b-it",
    "qwen3-vl-8b": "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
    "qwen3-vl-32b": "hosted_vllm/Qwen/Qwen3-VL-32B-Instruct",
    "internvl3-38b": "hosted_vllm/OpenGVLab/InternVL3-38B",
}


def test_paper_models_have_their_litellm_strings():
    profiles = get_plugin_host().profiles()
    assert {name: profiles[name].litellm_model for name in PAPER_MODELS} == PAPER_MODELS


@pytest.mark.parametrize("profile", PAPER_PROFILES, ids=lambda p: p.name)
def test_default_parser_is_a_registered_parser(profile):
    assert profile.default_parser in get_plugin_host().names("parser")


@pytest.mark.parametrize("profile", PAPER_PROFILES, ids=lambda p: p.name)
def test_backend_options_are_valid_litellm_backend_options(profile):
    from povagent_plugins.backends.litellm_backend import LiteLLMOptions

    LiteLLMOptions.model_validate({"model": profile.litellm_model, **profile.backend_options})


def test_paper_models_default_to_the_official_reading():
    # paper-comparable by default; repairs (rescale-1000 for 0-1000 answers, json) are opt-in
    paper = [p for p in PAPER_PROFILES if p.paper_name is not None]
    assert {p.name: p.default_parser for p in paper if p.default_parser != "official"} == {"robopoint": "robopoint-official"}


def test_vllm_models_need_an_api_base():
    assert all(p.needs_api_base == p.litellm_model.startswith("hosted_vllm/") for p in PAPER_PROFILES)


def test_robopoint_answers_given_only():
    robopoint = get_plugin_host().profile("robopoint")
    assert robopoint.conditions == (Condition.GIVEN,) and robopoint.default_parser == "robopoint-official"


def test_every_profile_documents_its_quirks():
    assert all(p.notes for p in PAPER_PROFILES)

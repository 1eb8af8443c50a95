"""Model profiles and their lookup (povagent/config/profiles.py)."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from povagent import hookimpl
from povagent.config.profiles import ModelProfile, resolve_profile
from povagent.dataset.release_models import Condition
from povagent.plugins import build_plugin_host


def test_profile_refuses_an_api_key_in_backend_options():
    with pytest.raises(ValidationError, match="api_key_env"):
        ModelProfile(name="m", litellm_model="openai/m", backend_options={"api_key": "sk-live"})


def test_profile_refuses_unknown_fields():
    with pytest.raises(ValidationError):
        ModelProfile(name="m", litellm_model="openai/m", parser="json")


def test_supports_lists_the_conditions_a_model_can_answer():
    p = ModelProfile(name="m", litellm_model="openai/m", conditions=(Condition.GIVEN,))
    assert p.supports("c") and not p.supports(Condition.INFERRED)


def test_resolve_profile_finds_a_builtin_profile():
    assert resolve_profile("gpt-5.4").litellm_model == "openai/gpt-5.4"


def test_resolve_profile_of_an_unknown_name_is_none():
    assert resolve_profile("no-such-model") is None


class _ThirdParty:
    """A throwaway plugin contributing one profile."""

    @hookimpl
    def register_model_profiles(self, register):
        register("my-model", ModelProfile(name="my-model", litellm_model="openai/my-model", default_parser="qwen"))


def test_resolve_profile_sees_third_party_profiles_through_the_host():
    host = build_plugin_host(entry_points=False)
    host.add_plugin(_ThirdParty(), name="third-party")
    try:
        assert resolve_profile("my-model", host=host).default_parser == "qwen"
    finally:
        host.remove_plugin("third-party")

"""Model profiles: short names for models with the defaults that make them work.

A profile ties a name a user writes in YAML (``model: gemini-robotics-er``) to a litellm model
string, the parser that reads that model family's answers, default strategy and backend
options, and the quirks a user should know (answers on 0-1000, a thinking budget that eats the
answer, conditions it cannot do). Plugins contribute profiles through the
``register_model_profiles`` hook; :func:`resolve_profile` looks one up.

This module only describes models: it never imports litellm and never calls a model.
"""

from __future__ import annotations

import difflib
import re
from typing import Any, Iterable, Mapping

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from povagent.config.remote_code import REMOTE_CODE_FLAG, REMOTE_CODE_OPTION, is_commit_hash
from povagent.dataset.release_models import CONDITIONS, Condition


class ModelProfile(BaseModel):
    """What povagent knows about one model.

    ``litellm_model`` is the model string litellm takes (``provider/name``); ``default_parser``
    is the parser name used when the pipeline names none; ``strategy_options`` and
    ``backend_options`` are defaults the pipeline's own options override; ``needs_api_base``
    says the model is self-hosted (vLLM) and the pipeline must give ``api_base``;
    ``api_key_env`` names the environment variable that usually holds the key (the key itself
    is never stored); ``conditions`` are those the model can answer; ``notes`` the quirks.

    ``backend`` is the backend ``model: <name>`` runs the profile with: ``litellm`` (a server or
    a provider, the default) or ``transformers`` (in-process). ``checkpoint`` is the Hugging
    Face id or folder the in-process backend loads, and ``checkpoint_options`` that backend's
    defaults (``dtype``, ``revision``...), kept apart from ``backend_options`` because
    the same profile may still be served behind an OpenAI-compatible server through litellm
    (``litellm_model``), whose options differ. ``remote_code`` says the checkpoint needs its own
    Python code: a profile never grants it (no ``trust_remote_code`` among its options); the
    user does, with ``--trust-remote-code`` (see :mod:`povagent.config.remote_code`), and a
    ``revision`` it pins is a commit hash.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = Field(min_length=1)
    litellm_model: str = Field(min_length=1)
    default_parser: str = "official"
    strategy_options: dict[str, Any] = Field(default_factory=dict)
    backend_options: dict[str, Any] = Field(default_factory=dict)
    needs_api_base: bool = False
    backend: str = Field("litellm", min_length=1)
    checkpoint: str | None = Field(None, min_length=1)
    checkpoint_options: dict[str, Any] = Field(default_factory=dict)
    remote_code: bool = False
    api_key_env: str | None = None
    conditions: tuple[Condition, ...] = CONDITIONS
    paper_name: str | None = None
    notes: str = ""

    @field_validator("backend_options")
    @classmethod
    def _no_secrets(cls, value: dict[str, Any]) -> dict[str, Any]:
        if "api_key" in value:
            raise ValueError("a profile must not carry an api_key; name the variable in api_key_env")
        return value

    @model_validator(mode="after")
    def _in_process_needs_a_checkpoint(self) -> ModelProfile:
        if self.backend == "transformers" and self.checkpoint is None:
            raise ValueError("a profile run in-process (backend: transformers) needs a checkpoint (a Hugging Face id or folder)")
        return self

    @model_validator(mode="after")
    def _never_grants_remote_code(self) -> ModelProfile:
        if REMOTE_CODE_OPTION in self.checkpoint_options or REMOTE_CODE_OPTION in self.backend_options:
            raise ValueError(f"a profile cannot grant {REMOTE_CODE_OPTION}; set remote_code: true (the user passes {REMOTE_CODE_FLAG})")
        revision = self.checkpoint_options.get("revision")
        if self.remote_code and revision is not None and not is_commit_hash(revision):
            raise ValueError(f"a profile needing remote code pins its revision to a commit hash, not {revision!r}")
        return self

    def supports(self, condition: Condition | str) -> bool:
        """Whether the model can answer instances of ``condition``."""
        return Condition(condition) in self.conditions


def near_profile(name: str, known: Iterable[str]) -> str | None:
    """The profile a bare model name (no ``provider/``) is a near miss of, or ``None``.

    Where a model string may be either a profile or a litellm model (the litellm backend's
    ``model`` option), an unknown bare name is a typo only when it is this close to a profile:
    the same after dropping case and ``-_.`` (``qwen3-vl8b``), or at least 90% alike
    (``gemini-robotic-er``). ``gpt-5`` or ``gpt-4o`` stay litellm model strings.
    """
    names = list(known)
    if "/" in name or name in names:
        return None
    flat = _flat(name)
    for candidate in names:
        if _flat(candidate) == flat:
            return candidate
    close = difflib.get_close_matches(name[:200], names, n=1, cutoff=0.9)
    return close[0] if close else None


def _flat(name: str) -> str:
    return re.sub(r"[-_.\s]", "", name.lower())


def resolve_profile(name: str, host: Any = None) -> ModelProfile | None:
    """The profile registered under ``name``, or ``None`` when there is none.

    Looks the name up through the plugin host (``host.profile(name)``; the process-wide host
    when ``host`` is None), so profiles from third-party plugins count too.
    """
    from povagent.errors import PluginError

    if host is None:
        from povagent.plugins import get_plugin_host

        host = get_plugin_host()
    try:
        found = host.profile(name)
    except PluginError:  # the host's "unknown profile" error
        return None
    if found is None or isinstance(found, ModelProfile):
        return found
    if isinstance(found, Mapping):
        return ModelProfile.model_validate(found)
    return ModelProfile.model_validate(found, from_attributes=True)

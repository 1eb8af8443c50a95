"""The ``litellm`` backend's options, checked before anything is called: a model or a router of
deployments, settings litellm's router knows, and never a literal API key (only the name of the
environment variable holding it).

:class:`LiteLLMOptions` validates a pipeline's ``backend.options``; :func:`options_error` turns a
validation failure into one :class:`~povagent.errors.ConfigError` naming the option. The calls
themselves are :mod:`povagent_plugins.backends.litellm_backend`'s.
"""

from __future__ import annotations

from typing import Any, Mapping

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from povagent.errors import ConfigError
from povagent.files.redaction import ENV_NAME_WANTED, Redactor

#: Router constructor settings a pipeline may set (litellm.Router keyword arguments).
ROUTER_SETTINGS = frozenset(
    {
        "num_retries",
        "timeout",
        "routing_strategy",
        "routing_strategy_args",
        "allowed_fails",
        "cooldown_time",
        "disable_cooldowns",
        "retry_after",
        "retry_policy",
        "enable_pre_call_checks",
        "default_max_parallel_requests",
    }
)

#: What a literal API key in the YAML is told.
KEY_MESSAGE = (
    "API keys are never read from YAML (it gets committed); export the key and name the "
    "variable instead: api_key_env: MY_KEY_VAR"
)


def _check_key_env(value: Any) -> Any:
    """Refuse an ``api_key_env`` that cannot be a variable name, without repeating the value."""
    if value is not None and not (isinstance(value, str) and Redactor().plausible_variable_name(value)):
        raise ValueError(ENV_NAME_WANTED)
    return value


#: Request headers that carry a credential (a key passed as a header is still a key in YAML).
_CREDENTIAL_HEADERS = frozenset({"authorization", "api-key", "x-api-key", "x-goog-api-key", "proxy-authorization"})


def _reject_literal_key(where: str, params: Mapping[str, Any]) -> None:
    if "api_key_env" in params:
        try:
            _check_key_env(params["api_key_env"])
        except ValueError as exc:
            raise ValueError(f"{where}.api_key_env: {exc}") from None
    key = params.get("api_key")
    # litellm's own "os.environ/NAME" form is a reference to the environment, not a key
    if key is not None and not (isinstance(key, str) and key.startswith("os.environ/")):
        raise ValueError(f"{where}: api_key given literally. {KEY_MESSAGE}")
    for name in ("extra_headers", "headers"):
        headers = params.get(name)
        if isinstance(headers, Mapping):
            secret = sorted(h for h in headers if str(h).lower() in _CREDENTIAL_HEADERS)
            if secret:
                raise ValueError(f"{where}: {name} carries a credential ({', '.join(secret)}). {KEY_MESSAGE}")


class LiteLLMOptions(BaseModel):
    """The ``backend.options`` of the litellm backend (unknown keys are errors)."""

    model_config = ConfigDict(extra="forbid")

    model: str | None = Field(None, min_length=1)
    api_base: str | None = None
    api_key_env: str | None = None
    temperature: float | None = Field(None, ge=0)
    max_tokens: int | None = Field(None, gt=0)
    timeout: float = Field(120.0, gt=0)
    extra: dict[str, Any] = Field(default_factory=dict)
    router: list[dict[str, Any]] | None = Field(None, min_length=1)
    router_settings: dict[str, Any] = Field(default_factory=dict)

    @field_validator("api_key_env", mode="before")
    @classmethod
    def _a_variable_name(cls, value: Any) -> Any:
        return _check_key_env(value)

    @field_validator("extra")
    @classmethod
    def _extra_has_no_key(cls, value: dict[str, Any]) -> dict[str, Any]:
        _reject_literal_key("extra", value)
        for name in ("num_retries", "max_retries"):
            if name in value:
                raise ValueError(f"extra: {name} is set by povagent (the runner or the Router retries)")
        return value

    @field_validator("router")
    @classmethod
    def _deployments_are_sound(cls, value: list[dict[str, Any]] | None) -> list[dict[str, Any]] | None:
        for i, dep in enumerate(value or []):
            params = dep.get("litellm_params") if isinstance(dep, Mapping) else None
            if not isinstance(params, Mapping) or not params.get("model"):
                raise ValueError(f"router[{i}]: needs litellm_params with a model (litellm Router model_list form)")
            _reject_literal_key(f"router[{i}].litellm_params", params)
        return value

    @field_validator("router_settings")
    @classmethod
    def _known_router_settings(cls, value: dict[str, Any]) -> dict[str, Any]:
        unknown = sorted(set(value) - ROUTER_SETTINGS)
        if unknown:
            raise ValueError(f"unknown router_settings {unknown}; known: {sorted(ROUTER_SETTINGS)}")
        return value

    @model_validator(mode="after")
    def _router_settings_need_a_router(self) -> LiteLLMOptions:
        if self.router_settings and self.router is None:
            raise ValueError("router_settings apply to a router: give router (the deployments) too, or drop them")
        return self


def options_error(exc: ValidationError) -> ConfigError:
    """The litellm backend's options refused in one line (a key in the YAML: :data:`KEY_MESSAGE`)."""
    from povagent.config.validation_messages import options_message  # the error path only

    return ConfigError(options_message("backend 'litellm'", exc, LiteLLMOptions, {"api_key": KEY_MESSAGE}))

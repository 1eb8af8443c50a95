"""The ``litellm`` backend: any model litellm can reach, named by one string in the YAML.

``model`` is a litellm model string (``openai/gpt-5.4``, ``gemini/gemini-2.5-flash``,
``hosted_vllm/Qwen/Qwen3-VL-8B-Instruct`` with ``api_base``) or a model profile name
(``gemini-robotics-er``). API keys come from the environment only: ``api_key_env`` names the
variable, read at call time and never stored in the identity, logs or rows; without it litellm
reads the provider's usual variable (``OPENAI_API_KEY``, ``GEMINI_API_KEY``). A profile's
backend options are defaults under the pipeline's, and a request of a condition the profile
cannot answer (RoboPoint: Given only) is refused as permanent without a call.

Retries: the runner retries :class:`TransientBackendError`, so direct calls run with litellm's
own retries off (``num_retries=0``). With ``router`` (a litellm Router ``model_list``: several
deployments of one model, e.g. vLLM replicas) the Router balances, rate-limits and retries
across deployments itself; a failure that outlives the Router's retries is raised as
:class:`PermanentBackendError` so the runner never stacks a second retry loop on top
(``retries_inside`` is True on such a backend).

Images travel inline (base64 data URLs) unless the pipeline sends them by reference
(``images: {transport: file | http}``): then only an OpenAI-compatible server named by
``api_base`` (``openai/...`` or ``hosted_vllm/...``, e.g. vLLM) receives ``file://`` or
``http://`` URLs; a hosted provider's own endpoint cannot fetch this machine's files, so
:meth:`LiteLLMBackend.check_image_transport` refuses the run before it starts.

litellm is imported in :meth:`LiteLLMBackend.start` (the runner and the agent call it before any
request's timeout starts), never when this module is imported, and in a worker thread: the
import takes seconds, and the event loop must keep going meanwhile. A run that will surely send
a request starts that import earlier, with :meth:`LiteLLMBackend.preload`, while it loads its
dataset; a run whose every answer is in the response cache never imports litellm.
"""

from __future__ import annotations

import asyncio
import json
import os
import time
from types import ModuleType
from typing import Any, ClassVar, Mapping

from pydantic import ValidationError

from povagent import hookimpl
from povagent.config.profiles import ModelProfile, near_profile, resolve_profile
from povagent.engine.llm_import import LiteLLMUnavailable, import_litellm_async, preload_litellm, warm_up_litellm_async
from povagent.engine.llm_logging import povagent_call, skip_truncation_when_unobserved
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.exchange.transport import ImageReferenceError
from povagent.interfaces import Backend, PermanentBackendError, TransientBackendError
from povagent.plugins import get_plugin_host, unknown_name_message
from povagent_plugins.backends.litellm_errors import map_litellm_error, unreachable_for_good
from povagent_plugins.backends.litellm_options import KEY_MESSAGE, LiteLLMOptions, options_error
from povagent_plugins.backends.openai_messages import openai_messages, tool_calls_of

#: litellm providers that send an OpenAI-style request to the ``api_base`` given, image URLs
#: untouched: the server there fetches ``file://``/``http://`` references itself.
REFERENCE_PROVIDERS = frozenset({"openai", "hosted_vllm"})
#: Router retries when the pipeline does not say (then the Router, not the runner, retries).
DEFAULT_ROUTER_RETRIES = 3
#: Extra time over the request timeout (times attempts) before a call is abandoned: a guard
#: against a client that never returns, not a timeout anyone should hit.
HARD_DEADLINE_SLACK_S = 30.0

def _jsonable(value: Any) -> Any:
    """``value`` made JSON-able (non-JSON leaves become their repr) for the identity."""
    return json.loads(json.dumps(value, sort_keys=True, default=repr))


#: What an OpenAI-compatible local server that needs no key (vLLM without ``--api-key``,
#: Ollama's ``/v1``) is sent in the key's place: the OpenAI client refuses to send a request
#: without one, and such a server reads none. A server that does need a key answers 401, which
#: the run reports as a missing key naming the variable to export.
NO_KEY = "no-key"

#: The litellm providers that speak the OpenAI API through the OpenAI client (which needs a key)
#: and read ``OPENAI_API_KEY`` when no key is given.
_OPENAI_CLIENT_PROVIDERS = ("openai/", "text-completion-openai/")


def keyless_placeholder(model: str, api_base: str | None) -> str | None:
    """:data:`NO_KEY` for an ``openai/...`` model on a server of its own (``api_base``) when
    ``OPENAI_API_KEY`` is not set, else ``None`` (litellm reads the provider's variable)."""
    if api_base and model.startswith(_OPENAI_CLIENT_PROVIDERS) and not os.environ.get("OPENAI_API_KEY"):
        return NO_KEY
    return None


class LiteLLMBackend(Backend):
    """Calls a model through litellm (one deployment, or a Router over several)."""

    cacheable: ClassVar[bool] = True

    def __init__(self, **options: Any) -> None:
        if options.get("api_key") is not None:
            raise ConfigError(f"backend 'litellm': option 'api_key': {KEY_MESSAGE}")
        profile = self._profile_for(options.get("model"))
        if profile is not None:
            options = self._with_profile_defaults(profile, options)
        try:
            opts = LiteLLMOptions.model_validate(options)
        except ValidationError as exc:
            raise options_error(exc) from None
        if opts.model is None and opts.router is None:
            raise ConfigError("backend 'litellm': option 'model': required (a litellm model string or a profile name)")
        if profile is not None and profile.needs_api_base and opts.api_base is None and opts.router is None:
            raise ConfigError(
                f"backend 'litellm': model {profile.name!r} is self-hosted ({profile.litellm_model}): "
                "set api_base (e.g. http://localhost:8000/v1) or a router of deployments"
            )
        self.profile: ModelProfile | None = profile
        self.options = opts
        self.model = opts.model or self._group_of(opts.router or [])
        self.retries_inside = opts.router is not None
        #: attempts the Router makes after the first (the runner widens its timeout by them)
        self.inner_retries = int(opts.router_settings.get("num_retries", DEFAULT_ROUTER_RETRIES)) if self.retries_inside else 0
        self._router: Any = None
        #: whether the server has ever answered (with anything): until then a refused connection
        #: means nothing listens at the address, and is not retried (see :meth:`complete`)
        self._reached = False

    # -- configuration ------------------------------------------------------------------------
    @staticmethod
    def _profile_for(model: Any) -> ModelProfile | None:
        # litellm strings carry a provider prefix; bare names may be profiles
        if not isinstance(model, str) or "/" in model:
            return None
        profile = resolve_profile(model)
        if profile is None:
            # a near miss of a profile is a typo, refused as under model: (not sent to litellm)
            known = get_plugin_host().names("profile")
            if near_profile(model, known) is not None:
                raise ConfigError(f"backend 'litellm': option 'model': {unknown_name_message('profile', model[:80], known)}")
        return profile

    @staticmethod
    def _with_profile_defaults(profile: ModelProfile, options: dict[str, Any]) -> dict[str, Any]:
        merged = {**profile.backend_options, **options, "model": profile.litellm_model}
        extra = {**profile.backend_options.get("extra", {}), **options.get("extra", {})}
        if extra:
            merged["extra"] = extra
        return merged

    @staticmethod
    def _group_of(router: list[dict[str, Any]]) -> str:
        names: set[str] = {d["model_name"] for d in router if d.get("model_name")}
        return names.pop() if len(names) == 1 else "povagent-router"

    def identity(self) -> Mapping[str, Any]:
        """Model, endpoint and answer-changing options; never a key or the key's value."""
        o = self.options
        ident: dict[str, Any] = {
            "backend": "litellm",
            "model": self.model,
            "api_base": o.api_base,
            "temperature": o.temperature,
            "max_tokens": o.max_tokens,
            "extra": _jsonable(o.extra),
        }
        if o.router is not None:
            # replicas of one model answer alike: the identity names the models, not the hosts
            ident["router_models"] = sorted({d["litellm_params"]["model"] for d in o.router})
        return ident

    def _api_key(self) -> str | None:
        name = self.options.api_key_env
        if name is None:
            return keyless_placeholder(self.model, self.options.api_base)
        value = os.environ.get(name)
        if not value:
            raise PermanentBackendError(
                f"environment variable {name} (api_key_env of backend 'litellm') is not set: export the API key",
                kind="missing_key",
            )
        return value

    def generation_kwargs(self, request: Request) -> dict[str, Any]:
        """Generation parameters sent: the strategy's, overridden by this backend's options."""
        params = request.generation.as_dict()
        o = self.options
        if o.temperature is not None:
            params["temperature"] = o.temperature
        if o.max_tokens is not None:
            params["max_tokens"] = o.max_tokens
        params.update(o.extra)
        return params

    # -- image transport ----------------------------------------------------------------------
    def _deployments_refusing_references(self) -> list[str]:
        """The model strings (with why) that cannot be sent ``file://``/``http://`` image URLs."""
        o = self.options
        deployments = (
            [(d["litellm_params"]["model"], d["litellm_params"].get("api_base")) for d in o.router]
            if o.router is not None
            else [(self.model, o.api_base)]
        )
        refused = []
        for model, api_base in deployments:
            provider = str(model).split("/", 1)[0] if "/" in str(model) else None
            if provider not in REFERENCE_PROVIDERS:
                refused.append(f"{model} (provider {provider or 'inferred by litellm'}: not an OpenAI-compatible server)")
            elif not api_base:
                refused.append(f"{model} (no api_base: the provider's own endpoint)")
        return refused

    def check_image_transport(self, transport: str) -> None:
        """Refuse ``file``/``http`` unless every deployment is an OpenAI-compatible server at an
        ``api_base`` (``openai/...`` or ``hosted_vllm/...``): a hosted provider cannot read this
        machine's files or reach its static server."""
        if transport == "inline":
            return
        refused = self._deployments_refusing_references()
        if refused:
            raise ConfigError(
                f"images: transport {transport} sends image references (URLs) the model server must fetch itself, "
                f"which only an OpenAI-compatible server at an api_base can (model openai/... or hosted_vllm/... "
                f"with api_base, e.g. vLLM); refused for {'; '.join(refused)}. Use images: {{transport: inline}} "
                f"for hosted providers."
            )

    def _messages(self, request: Request, images: ImageStore) -> list[dict[str, Any]]:
        """The request in OpenAI form; images by the store's transport (references only where allowed)."""
        transport = images.transport if images is not None else None  # a text-only request may come without a store
        if transport is not None and transport.name != "inline" and self._deployments_refusing_references():
            # an embedding that skipped check_image_transport: fail clearly, never send a
            # reference a hosted provider cannot fetch
            raise PermanentBackendError(
                f"image transport {transport.name} needs an OpenAI-compatible server at an api_base; "
                f"{self.model} is not one (use inline)"
            )
        try:
            return openai_messages(request, images)
        except ImageReferenceError as exc:  # a frame outside the served folders: no retry fixes it
            raise PermanentBackendError(f"image cannot be sent by reference: {exc}") from None

    # -- calling ------------------------------------------------------------------------------
    def _check_condition(self, request: Request) -> None:
        # a profile that cannot answer a condition (RoboPoint: Given only) is refused before
        # any paid call, with the reason, instead of failing slowly or answering nonsense
        # (an external multiple-choice item has no condition: nothing to refuse)
        profile, instance = self.profile, request.instance
        if profile is not None and instance is not None and instance.condition is not None and not profile.supports(instance.condition):
            allowed = ", ".join(f"{c.label} ({c.value})" for c in profile.conditions)
            raise PermanentBackendError(
                f"model profile {profile.name!r} answers {allowed} only, not {instance.condition.label} "
                f"({instance.condition.value}); restrict instances.conditions for this model"
            )

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Send ``request`` (images in order, by the store's transport); raise Transient/Permanent errors."""
        self._check_condition(request)
        # messages first: a request that cannot be sent fails before the (slow) first import
        kwargs = {"messages": self._messages(request, images), **self.generation_kwargs(request)}
        if request.tools:
            kwargs["tools"] = [dict(t) for t in request.tools]
        litellm = _LITELLM or await _import_litellm_off_loop()
        key: str | None = None
        attempts = 1
        started = time.perf_counter()
        try:
            if self.options.router is not None:
                router = self._get_router(litellm)
                attempts += int(router.num_retries or 0)
                call = router.acompletion(model=self.model, timeout=self.options.timeout, **kwargs)
            else:
                key = self._api_key()
                call = litellm.acompletion(
                    model=self.model,
                    api_base=self.options.api_base,
                    api_key=key,
                    timeout=self.options.timeout,
                    num_retries=0,  # the runner retries; litellm must not retry underneath it
                    max_retries=0,
                    **kwargs,
                )
            # marked as ours: litellm skips shortening its base64 for logging while nothing
            # can read that payload (povagent.engine.llm_logging)
            with povagent_call(kwargs):
                async with asyncio.timeout(self.options.timeout * attempts + HARD_DEADLINE_SLACK_S):
                    response = await call
        except TimeoutError as exc:
            if self.retries_inside:
                raise PermanentBackendError("no answer within the hard deadline after Router retries") from exc
            raise TransientBackendError(f"no answer within {self.options.timeout:g} s (hard deadline)", kind="timeout") from exc
        except (PermanentBackendError, TransientBackendError):
            raise
        except Exception as exc:
            mapped = map_litellm_error(
                litellm, exc, secrets=self._secrets(key), retried_inside=self.retries_inside, url=self._endpoint()
            )
            if mapped is exc:
                raise
            if getattr(mapped, "kind", None) != "connection":
                self._reached = True  # the server answered, if only with an error
            elif not self._reached and (why := unreachable_for_good(exc)) is not None:
                # nothing listens there (a wrong port, a server not started): retrying for a
                # minute cannot help. Once the server has answered, a refusal is a restart and
                # stays transient (retried within the run's retry policy).
                raise PermanentBackendError(
                    f"cannot reach {self._endpoint()} ({why}) before the server ever answered: "
                    "start the server or fix api_base",
                    status=getattr(mapped, "status", None),
                    kind="connection",
                ) from exc
            raise mapped from exc
        self._reached = True
        latency = time.perf_counter() - started
        calls = tool_calls_of(response) if request.tools else ()
        return Response(
            text="" if calls and _content_of(response) is None else _text_of(response),
            usage=_usage_of(litellm, response),
            latency_s=latency,
            model=getattr(response, "model", None),
            tool_calls=calls,
        )

    def _endpoint(self) -> str:
        """Where requests go, for messages: ``api_base``, the Router's deployments, or the
        provider's own endpoint (named by the model string)."""
        if self.options.api_base:
            return self.options.api_base
        if self.options.router:
            bases = sorted({str(d["litellm_params"].get("api_base") or d["litellm_params"]["model"]) for d in self.options.router})
            return ", ".join(bases)
        return f"the provider's endpoint for {self.model}"

    def _secrets(self, key: str | None) -> tuple[str, ...]:
        names = [self.options.api_key_env] + [
            d["litellm_params"].get("api_key_env") for d in (self.options.router or [])
        ]
        values = [os.environ.get(n, "") for n in names if n]
        return tuple(v for v in [key, *values] if v and v != NO_KEY)

    def _get_router(self, litellm: Any) -> Any:
        # built on first use: litellm is imported lazily, and keys are read from the environment
        # only now
        if self._router is None:
            settings = {
                "num_retries": DEFAULT_ROUTER_RETRIES,
                "timeout": self.options.timeout,
                **self.options.router_settings,
            }
            self._router = litellm.Router(model_list=self._deployments(), **settings)
        return self._router

    def _deployments(self) -> list[dict[str, Any]]:
        out = []
        for dep in self.options.router or []:
            params = dict(dep["litellm_params"])
            env = params.pop("api_key_env", None)
            if env:
                value = os.environ.get(env)
                if not value:
                    raise PermanentBackendError(
                        f"environment variable {env} (api_key_env of router deployment {dep.get('model_name') or params.get('model')}) "
                        f"is not set: export the API key",
                        kind="missing_key",
                    )
                params["api_key"] = value
            out.append({**dep, "model_name": self.model, "litellm_params": params})
        return out

    def preload(self) -> None:
        """Import litellm and warm it up in a background thread (see
        :func:`~povagent.engine.llm_import.preload_litellm`); :meth:`start` waits for it."""
        preload_litellm(self._warm_up_model())

    def _warm_up_model(self) -> str:
        # a Router's group name is no litellm model string: warm up with a deployment's
        return self.options.router[0]["litellm_params"]["model"] if self.options.router else self.model

    async def start(self) -> None:
        """Import litellm (seconds, the first time) in a worker thread before any request's
        timeout starts; a missing API key is found here, before the run fans out. litellm's
        base64 truncation for logging is skipped for our calls from here on whenever nothing
        can read its logging payload (:mod:`povagent.engine.llm_logging`).

        An ``api_key_env`` naming an unset variable (the backend's own, or a router
        deployment's) is a :class:`PermanentBackendError` raised first, before the import: the
        run stops at once, with nothing sent."""
        if self.options.router is None:
            self._api_key()
        else:
            self._deployments()
        if _LITELLM is None:
            await _import_litellm_off_loop()
        await warm_up_litellm_async(self._warm_up_model())

    async def aclose(self) -> None:
        """Drop the Router (its clients are litellm's shared, cached ones)."""
        self._router = None


#: litellm, once imported (a module global: the import is process-wide anyway).
_LITELLM: ModuleType | None = None


async def _import_litellm_off_loop() -> ModuleType:
    """Import litellm off the event loop (seconds, the first time; bounded and cancellable: see
    :mod:`povagent.engine.llm_import`). An import that fails is a permanent failure of kind
    ``client_import``: the run stops at its first key with one line, nothing sent."""
    global _LITELLM
    try:
        litellm = await import_litellm_async()
    except LiteLLMUnavailable as exc:
        raise PermanentBackendError(str(exc), kind="client_import") from None
    skip_truncation_when_unobserved(litellm)
    _LITELLM = litellm
    return litellm


def _content_of(response: Any) -> Any:
    try:
        return response.choices[0].message.content
    except (AttributeError, IndexError, TypeError):
        return None


def _text_of(response: Any) -> str:
    """The answer's text. No choice at all, or a choice whose content is null, is no answer:
    a transient failure (retried, never cached), not an empty answer kept forever."""
    try:
        choices = response.choices
        content = choices[0].message.content
    except (AttributeError, IndexError, TypeError):
        raise TransientBackendError("the server answered with no choices (empty response)", kind="empty_response") from None
    if content is None:
        reason = getattr(choices[0], "finish_reason", None)
        raise TransientBackendError(
            f"the server answered with null content (finish_reason {reason!r})", kind="empty_response"
        )
    return content if isinstance(content, str) else str(content)


def _usage_of(litellm: Any, response: Any) -> Usage:
    usage = getattr(response, "usage", None)
    return Usage(
        prompt_tokens=getattr(usage, "prompt_tokens", None),
        completion_tokens=getattr(usage, "completion_tokens", None),
        cost_usd=_cost_of(litellm, response),
    )


def _cost_of(litellm: Any, response: Any) -> float | None:
    """The call's cost in USD, or ``None`` for a model without a price (self-hosted, test
    servers). litellm has already priced the response before returning it (``response_cost``
    in its hidden parameters, ``None`` when the model has no price); pricing it again costs
    0.2-0.4 ms of CPU per request, and an exception per request for unpriced models."""
    hidden = getattr(response, "_hidden_params", None)
    if isinstance(hidden, Mapping) and "response_cost" in hidden:
        cost = hidden["response_cost"]
        return float(cost) if isinstance(cost, int | float) else None
    try:  # a response litellm did not price on the way (none seen with the pinned version)
        return float(litellm.completion_cost(completion_response=response))
    except Exception:  # unknown models (self-hosted, test servers) have no price: not an error
        return None


@hookimpl
def register_backends(register) -> None:
    """Contribute the litellm backend."""
    register(
        "litellm",
        LiteLLMBackend,
        description="Any litellm model string or model profile; a Router over several deployments",
    )

"""The ``transformers`` backend: a checkpoint evaluated in this process, no server.

``backend: {name: transformers, options: {model: PATH_OR_ID, dtype, device_map, max_batch: 8,
attn_implementation, sampling, revision}}``. ``model``
is a folder, a Hugging Face id, or a model profile run in-process (``qwen3-vl-8b-transformers``,
``molmopoint-8b``: the profile's ``checkpoint`` and ``checkpoint_options`` are defaults under the
pipeline's options). Needs ``torch`` (installed first, for the hardware) and ``povagent[local]``.

A checkpoint's own Python code runs only when the command line or the Python call granted it
(:mod:`povagent.config.remote_code`), never because an option or a profile says so; a folder is
checked before ``transformers`` reads it (:mod:`povagent_plugins.backends.checkpoint_checks`).

Requests take the one request path every backend takes (response cache, resume, concurrency,
timeouts): the runner calls :meth:`TransformersBackend.complete` concurrently, and a batching
queue (:mod:`povagent_plugins.backends.local_batching`) groups the requests waiting into
``generate`` calls of up to ``max_batch``, so a GPU is kept busy; give the pipeline a
``concurrency`` of at least ``max_batch``. Greedy decoding gives the same answers batched or
one at a time (tested on the tiny checkpoints).

One model per process: it is loaded once, in a daemon thread of its own (the event loop keeps
running, and a stop never waits for a load that does not end),
by :meth:`~TransformersBackend.start`; a second backend on the same checkpoint and settings
shares it, one on another checkpoint meanwhile is refused; it is freed when the last backend
using it closes. Running out of device memory is
never retried as such: the batch is split and run again, and a single request that still does
not fit is a permanent failure of kind ``out_of_memory`` (a typed row).

The identity (rows' ``model`` and the cache key) names the checkpoint and a fingerprint of its
files (:mod:`povagent_plugins.backends.local_checkpoint`), so a checkpoint trained again into
the same folder never reads the old answers from the cache.
"""

from __future__ import annotations

import asyncio
import re
import threading
import time
from pathlib import Path
from typing import Any, ClassVar, Literal, Mapping

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from povagent import hookimpl
from povagent.config.profiles import ModelProfile, resolve_profile
from povagent.config.remote_code import FROM_A_FILE, check_pinned_revision, needs_the_flag, remote_code_allowed
from povagent.engine.daemon_threads import in_daemon_thread
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.interfaces import Backend, PermanentBackendError
from povagent_plugins.backends.checkpoint_checks import check_checkpoint_folder
from povagent_plugins.backends.local_batching import BatchQueue, LocalOutOfMemory
from povagent_plugins.backends.local_checkpoint import checkpoint_fingerprint, checkpoint_folder, checkpoint_label
from povagent_plugins.backends.local_model import (
    Conversation,
    Decoding,
    Generated,
    LoadSettings,
    LocalModel,
    conversation_of,
    decoding_of,
    is_out_of_memory,
)
from povagent_plugins.backends.point_reader import read_points, reads_points


class TransformersOptions(BaseModel):
    """The ``backend.options`` of the ``transformers`` backend (unknown keys are errors)."""

    model_config = ConfigDict(extra="forbid")

    model: str = Field(min_length=1)
    dtype: Literal["auto", "float32", "bfloat16", "float16"] = "auto"
    device_map: str | dict[str, Any] | None = None
    #: never true here: remote code is granted by the call, not an option (false is accepted)
    trust_remote_code: bool = False
    max_batch: int = Field(8, ge=1, le=256)
    attn_implementation: str | None = None
    #: decoding of a request that sets no temperature: greedy, or the checkpoint's generation_config
    sampling: Literal["greedy", "checkpoint"] = "greedy"
    revision: str | None = None

    @field_validator("trust_remote_code")
    @classmethod
    def _not_from_options(cls, value: bool) -> bool:
        if value:
            raise ValueError(FROM_A_FILE)
        return value

    def load_settings(self, remote_code: bool) -> LoadSettings:
        """What loading the checkpoint needs (``remote_code``: granted by the call)."""
        return LoadSettings(
            model=self.model,
            dtype=self.dtype,
            device_map=self.device_map,
            trust_remote_code=remote_code,
            attn_implementation=self.attn_implementation,
            revision=self.revision,
        )


#: A Hugging Face id: ``name`` or ``owner/name``.
_HUB_ID = re.compile(r"^[A-Za-z0-9][\w.-]*(/[\w.-]+)?$")


def _check_model_location(model: str) -> None:
    """Refuse a ``model`` that is neither an existing folder nor shaped like a Hub id (a path
    with a typo), before anything is loaded, in one line naming the option."""
    path = Path(model).expanduser()
    if path.is_dir():
        return
    if path.exists():
        raise ConfigError(f"backend 'transformers': option 'model': {model} is a file; give the checkpoint's folder")
    if not _HUB_ID.match(model) or model.startswith((".", "~")):
        raise ConfigError(
            f"backend 'transformers': option 'model': no folder {model} (give a checkpoint folder, a Hugging Face id "
            "owner/name, or an in-process model profile)"
        )


class _LoadedModel:
    """The process's one loaded model, shared by the backends that use the same settings."""

    lock = threading.Lock()
    local: LocalModel | None = None
    users = 0

    @classmethod
    def acquire(cls, settings: LoadSettings) -> LocalModel:
        """The loaded model for ``settings``, loading it if needed; a different checkpoint
        while another is in use is refused (two 8B models rarely fit one device)."""
        with cls.lock:
            if cls.local is not None and cls.local.settings.key() == settings.key():
                cls.users += 1
                return cls.local
            if cls.local is not None:  # freed when its last user closed: still in use
                raise PermanentBackendError(
                    f"another checkpoint ({cls.local.settings.model}) is loaded in this process and in use; "
                    "one model per process: close its pipeline or agent first, or run this one in another process",
                    kind="model_busy",
                )
            cls.local = LocalModel.load(settings)
            cls.users = 1
            return cls.local

    @classmethod
    def release(cls, local: LocalModel) -> None:
        """One user fewer; the last one frees the model."""
        with cls.lock:
            if cls.local is not local:
                return
            cls.users -= 1
            if cls.users <= 0:
                local.free()
                cls.local = None
                cls.users = 0


class TransformersBackend(Backend):
    """Runs a Hugging Face checkpoint in-process, batching concurrent requests."""

    cacheable: ClassVar[bool] = True

    def __init__(self, **options: Any) -> None:
        profile = self._profile_for(options.get("model"))
        if profile is not None:
            options = {**profile.checkpoint_options, **options, "model": profile.checkpoint}
        try:
            self.options = TransformersOptions.model_validate(options)
        except ValidationError as exc:
            from povagent.config.validation_messages import options_message  # the error path only

            raise ConfigError(options_message("backend 'transformers'", exc, TransformersOptions)) from None
        _check_model_location(self.options.model)
        self.profile: ModelProfile | None = profile
        #: whether the checkpoint's own code may run: granted by the call making this backend
        self.remote_code = remote_code_allowed()
        self._check_remote_code()
        folder = checkpoint_folder(self.options.model, self.options.revision)
        if folder is not None:  # a Hub id not downloaded yet is fetched and read by transformers
            check_checkpoint_folder(folder)
        self._fingerprint: str | None = None
        self._local: LocalModel | None = None
        self._queue: BatchQueue[tuple[Request, ImageStore, Decoding], Generated] | None = None
        self._loading: asyncio.Task[None] | None = None

    def _check_remote_code(self) -> None:
        """A profile needing its checkpoint's code without the grant, or a granted Hub
        checkpoint whose revision is a branch or a ref, is refused in one line."""
        model, revision = self.options.model, self.options.revision
        if self.remote_code:
            check_pinned_revision(model, revision, hub_id=not Path(model).expanduser().is_dir())
        elif self.profile is not None and self.profile.remote_code:
            raise ConfigError(needs_the_flag(f"model profile {self.profile.name!r} ({model})", revision))

    @staticmethod
    def _profile_for(model: Any) -> ModelProfile | None:
        if not isinstance(model, str) or "/" in model:
            return None
        profile = resolve_profile(model)
        if profile is None:
            return None
        if profile.checkpoint is None:
            raise ConfigError(
                f"backend 'transformers': option 'model': profile {model!r} has no checkpoint to run in-process "
                f"(use backend litellm for it, or give a folder or Hugging Face id)"
            )
        return profile

    # -- identity -----------------------------------------------------------------------------
    def fingerprint(self) -> str | None:
        """The checkpoint's fingerprint (``None`` for a Hub id not downloaded yet)."""
        if self._fingerprint is None:
            folder = checkpoint_folder(self.options.model, self.options.revision)
            self._fingerprint = checkpoint_fingerprint(folder) if folder is not None else None
        return self._fingerprint

    def identity(self) -> Mapping[str, Any]:
        """The checkpoint (path or id, with its fingerprint) and what changes its answers."""
        o = self.options
        return {
            "backend": "transformers",
            "model": checkpoint_label(o.model, self.fingerprint()),
            "checkpoint_sha256": self.fingerprint(),
            "revision": o.revision,
            "dtype": o.dtype,
            "sampling": o.sampling,
            "attn_implementation": o.attn_implementation,
            "trust_remote_code": self.remote_code,
        }

    # -- lifecycle ----------------------------------------------------------------------------
    async def start(self) -> None:
        """Load the checkpoint (once per process) in a daemon thread.

        Every request that arrives while it loads waits on the same load and wakes with the
        others at once, so the first batch is as full as the later ones. A load that failed
        fails every later call the same way (a missing file does not appear by retrying), except
        ``model_busy``: once the other checkpoint is closed, this one loads."""
        if self._queue is not None:
            return
        if self._loading is None or _busy(self._loading):
            self._loading = asyncio.get_running_loop().create_task(self._load())
        await asyncio.shield(self._loading)

    async def _load(self) -> None:
        try:
            # a daemon thread, not the default executor: a load that never ends (a checkpoint's
            # own code, a file system that hangs) must not keep a stopped run from exiting
            settings = self.options.load_settings(self.remote_code)
            self._local = await in_daemon_thread(lambda: _LoadedModel.acquire(settings), "povagent-load-checkpoint")
        except ImportError as exc:
            raise PermanentBackendError(
                f"the transformers backend needs torch and transformers ({exc}): install torch for your "
                "hardware first, then pip install 'povagent[local]'",
                kind="missing_dependency",
            ) from None
        except PermanentBackendError:
            raise
        except (OSError, ValueError) as exc:
            if not self.remote_code and "trust_remote_code" in str(exc):  # transformers met an auto_map
                reason = needs_the_flag(f"checkpoint {self.options.model}", self.options.revision)
                raise PermanentBackendError(reason, kind="load_failed") from None
            raise PermanentBackendError(f"cannot load checkpoint {self.options.model}: {exc}", kind="load_failed") from None
        max_batch = 1 if reads_points(self._local.model) else self.options.max_batch
        self._queue = BatchQueue(self._run_batch, max_batch)

    async def aclose(self) -> None:
        """Stop the queue and let the model go (freed when no other backend uses it)."""
        if self._queue is not None:
            await self._queue.aclose()
            self._queue = None
        self._loading = None
        if self._local is not None:
            local, self._local = self._local, None
            await asyncio.to_thread(_LoadedModel.release, local)

    @property
    def batch_stats(self) -> Any:
        """The batching queue's counts (batches, largest, splits), or ``None`` before start."""
        return self._queue.stats if self._queue is not None else None

    # -- answering ----------------------------------------------------------------------------
    def _run_batch(self, items: list[tuple[Request, ImageStore, Decoding]]) -> list[Generated]:
        """One batch (same decoding), in the queue's worker thread: images are decoded here,
        off the event loop, so requests reach the queue the moment they are sent."""
        local = self._local
        if local is None or local.freed:
            raise PermanentBackendError("the transformers backend was closed", kind="closed")
        conversations: list[Conversation] = [conversation_of(request, images) for request, images, _ in items]
        decoding = items[0][2]
        try:
            if reads_points(local.model):
                return read_points(local, conversations, decoding)
            return local.generate(conversations, decoding)
        except Exception as exc:
            if is_out_of_memory(exc):
                local.release_cached_memory()
                raise LocalOutOfMemory(f"out of memory generating a batch of {len(items)}: {exc}") from exc
            raise

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer ``request`` in a batch with others waiting; out of memory alone is permanent."""
        if self._queue is None:
            await self.start()
        assert self._queue is not None
        decoding = decoding_of(request, self.options.sampling)
        started = time.perf_counter()
        try:
            generated = await self._queue.submit((request, images, decoding), group=decoding)
        except LocalOutOfMemory as exc:
            raise PermanentBackendError(f"{exc} (lower max_batch or the processor's image size)", kind="out_of_memory") from None
        return Response(
            text=generated.text,
            usage=Usage(prompt_tokens=generated.prompt_tokens, completion_tokens=generated.completion_tokens),
            latency_s=time.perf_counter() - started,
            model=checkpoint_label(self.options.model, self.fingerprint()),
        )


def _busy(loading: asyncio.Task[None]) -> bool:
    """Whether a finished load was refused because another checkpoint was in use."""
    if not loading.done() or loading.cancelled():
        return loading.cancelled()
    exc = loading.exception()
    return isinstance(exc, PermanentBackendError) and exc.kind == "model_busy"


@hookimpl
def register_backends(register) -> None:
    """Contribute the in-process transformers backend."""
    register(
        "transformers",
        TransformersBackend,
        description="A Hugging Face checkpoint run in this process (torch + povagent[local]); batches concurrent requests",
    )

"""The base classes a plugin implements: backends, strategies, parsers, scorers.

A plugin registers a *factory* (usually one of these subclasses) under a name through the
``register_*`` hooks in :mod:`povagent.hookspecs`; the runner calls ``factory(**options)`` with
the options from the pipeline YAML. Everything here is abstract: no file, network or clock.
"""

from __future__ import annotations

import abc
from typing import TYPE_CHECKING, Any, Awaitable, Callable, ClassVar, Mapping

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.exchange.messages import Request, Response

if TYPE_CHECKING:
    from povagent.dataset.instances import Instance
    from povagent.dataset.protocol import EvaluationSet
    from povagent.exchange.images import ImageStore

#: What a multi-turn strategy calls to talk to the model: cached, retried, rate-limited.
Ask = Callable[[Request], Awaitable[Response]]


class TransientBackendError(Exception):
    """A failure worth retrying: timeout, dropped connection, 429, 5xx, an empty answer.

    ``retry_after`` (seconds) is honoured when the server sent one. ``kind`` optionally names
    the failure for the row's ``error_type`` (``"connection"``, ``"timeout"``,
    ``"empty_response"``); without it the kind follows ``status``.
    """

    def __init__(
        self, message: str, *, retry_after: float | None = None, status: int | None = None, kind: str | None = None
    ) -> None:
        super().__init__(message)
        self.retry_after = retry_after
        self.status = status
        self.kind = kind


class PermanentBackendError(Exception):
    """A failure not worth retrying: bad request, authentication, unknown model (4xx), a
    missing API key. ``kind`` optionally names it (``"missing_key"``)."""

    def __init__(self, message: str, *, status: int | None = None, kind: str | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.kind = kind


class Backend(abc.ABC):
    """A model (or an offline baseline) that answers requests.

    Subclasses take their YAML options as keyword arguments. ``identity()`` must describe
    everything that changes answers (it is part of the cache key) and nothing secret.
    """

    #: Whether answers may be cached (offline baselines that are instant can say False).
    cacheable: ClassVar[bool] = True

    @abc.abstractmethod
    def identity(self) -> Mapping[str, Any]:
        """JSON-able identity: model name and answer-changing options; never API keys."""

    @abc.abstractmethod
    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer one request. Raise TransientBackendError / PermanentBackendError on failure."""

    async def start(self) -> None:  # noqa: B027 - optional hook
        """Get ready before the first request (import a client library, open a pool).

        Called once by the runner (when its first request misses the response cache) and
        by the agent, before any request's timeout starts, so a slow import never counts
        against the first requests' time. The default does nothing.
        """

    def preload(self) -> None:  # noqa: B027 - optional hook
        """Start loading client libraries in the background and return at once.

        The runner calls it at its very start when a request will surely be sent (no row in
        the run folder yet, no response cache to answer from), so a slow import overlaps the
        loading of the dataset; :meth:`start` still follows, and must wait for what this
        began. The default does nothing.
        """

    async def aclose(self) -> None:  # noqa: B027 - optional hook
        """Release connections; called once when the run ends."""

    def check_image_transport(self, transport: str) -> None:  # noqa: B027 - optional hook
        """Raise :class:`povagent.errors.ConfigError` if this backend cannot send images by
        ``transport`` (``"inline"``, ``"file"`` or ``"http"``, see
        :mod:`povagent.exchange.transport`); called before a run starts. The default accepts
        all: a backend that sends images takes their URLs from ``ImageStore.url``, which follows
        the transport, and one that sends none (an offline baseline) is not concerned.
        """


class Strategy(abc.ABC):
    """How a model is asked: prompt text, images (perhaps marked) and the answer format."""

    @abc.abstractmethod
    def build(self, instance: Instance, images: ImageStore) -> Request:
        """The (first) request for an instance."""

    def answer_spec(self, instance: Instance) -> AnswerSpec | None:
        """What the strategy asks ``instance`` to answer, without building a request.

        Used to re-parse finished runs offline (``povagent rescore``). Returning ``None``
        (the default) makes callers build the full request instead, which reads the images.
        """
        return None

    async def solve(self, instance: Instance, ask: Ask, images: ImageStore) -> list[tuple[Request, Response]]:
        """Talk to the model and return every exchange, the final answer last.

        The default is single-turn: build one request and ask once. Multi-turn strategies
        (self-checking, tool use) override this and may call ``ask`` several times.
        """
        request = self.build(instance, images)
        return [(request, await ask(request))]


class Parser(abc.ABC):
    """Reads a point (and a frame) out of a model's raw answer. Must never raise on bad text."""

    @abc.abstractmethod
    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """A typed parse of ``text`` given what was asked (``spec``)."""


class Scorer(abc.ABC):
    """Scores one parsed answer against the ground truth."""

    @abc.abstractmethod
    def score(self, instance: Instance, answer: ParsedAnswer, dataset: EvaluationSet | None) -> dict[str, Any]:
        """JSON-able scores for one row (e.g. ``{"answered": True, "l2": 0.12, ...}``)."""

"""The one way a request reaches a model: cache, concurrency limit, timeout, retries.

The runner (every key of a pipeline) and the embedded agent (one ``locate`` call) both send
requests through :class:`RequestPath`, so they share one retry policy type
(:class:`~povagent.config.retry_policy.RetryPolicy`), one transient/permanent classification
(:func:`~povagent.engine.retry.is_transient`), one timeout rule (:meth:`RequestPath.attempt_timeout`)
and, optionally, the response cache.

How one request goes: a cached answer is returned at once (a failure is never cached); else the
backend is called under the concurrency limit and cut at the attempt timeout (or at the time
left before the caller's deadline, whichever is sooner); a transient failure is retried after
:func:`~povagent.engine.retry.wait_before_retry` while attempts and the deadline allow, with
tenacity driving attempts 2..n (the first attempt runs bare: the common case pays nothing for
retries); the last failure, or a permanent one, becomes an
:class:`~povagent.engine.retry.InfraFailure` whose message names what failed and whose
``attempts`` counts every try. A backend that retries inside (litellm's Router) gets one
attempt: a second retry loop must never stack on top of its own.

This module knows nothing of datasets, rows or run folders.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
import traceback
from dataclasses import dataclass
from typing import Any, AsyncContextManager, Callable, Protocol

from tenacity import AsyncRetrying, retry_if_exception, stop_after_attempt

from povagent.config.retry_policy import RetryPolicy
from povagent.engine.cache import ResponseCache, cache_key, identity_json
from povagent.engine.received import received
from povagent.engine.retry import InfraFailure, error_type_of, is_transient, wait_before_retry
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.interfaces import Backend


class Limiter(Protocol):
    """What bounds the requests in flight: an ``asyncio.Semaphore`` or an adaptive limiter.

    ``slot()`` is entered around each attempt; an adaptive limiter may also hear how each
    attempt ended (``record(exc)``, ``exc`` being ``None`` on success).
    """

    def slot(self) -> AsyncContextManager[Any]: ...


@dataclass
class PathStats:
    """What went through the path: attempts made, answers from the cache, retries."""

    requests: int = 0
    cache_hits: int = 0
    retries: int = 0


#: Called before each wait between attempts: (label, the failure, failed attempts so far, wait s).
OnRetry = Callable[[str, BaseException, int, float], None]
#: Called when an attempt raised something that is no API failure (a plugin bug), with its
#: label, the redacted message and the formatted traceback.
OnBug = Callable[[str, str, str], None]


def _identity(text: str) -> str:
    return text


class RequestPath:
    """Sends requests to one backend: cached, limited, timed out and retried.

    ``timeout_s`` is the per-attempt timeout (a backend that retries inside gets room for its
    own attempts: see :meth:`attempt_timeout`); ``cache`` is optional (and ignored for a backend
    that is not ``cacheable``); ``limiter`` defaults to no limit; ``redact`` scrubs secrets from
    every message that leaves this path, and ``redact_answer`` the secret values povagent knows
    from every string of every answer (fresh or cached; text, model name, tool calls), before
    the strategy, the cache, the row or the log sees it: a server may echo the ``Authorization``
    header anywhere in a successful answer (see :mod:`povagent.engine.received`).
    """

    def __init__(
        self,
        backend: Backend,
        images: ImageStore,
        *,
        policy: RetryPolicy,
        timeout_s: float,
        cache: ResponseCache | None = None,
        limiter: Limiter | None = None,
        redact: Callable[[str], str] = _identity,
        redact_answer: Callable[[str], str] = _identity,
        on_retry: OnRetry | None = None,
        on_bug: OnBug | None = None,
        start_backend: bool = False,
    ) -> None:
        self.backend = backend
        self.images = images
        self.policy = policy
        self.timeout_s = float(timeout_s)
        self.cache = cache if getattr(backend, "cacheable", True) else None
        self.limiter = limiter
        self.redact = redact
        self.redact_answer = redact_answer
        self.on_retry = on_retry
        self.on_bug = on_bug
        self.stats = PathStats()
        self._identity = identity_json(backend.identity()) if self.cache is not None else ""
        #: with ``start_backend``, the backend's start, begun by the first request the cache
        #: cannot answer (a run whose every answer is cached never starts it)
        self._start: asyncio.Future[None] | None = None
        self._start_backend = start_backend
        #: the start has succeeded (a start, once done, stays done)
        self._running = False
        #: a backend answering in this process (:attr:`Backend.answers_in_process`) is called
        #: bare: a slot or a timeout cannot act on a call that never suspends, and each cost a
        #: run's offline baseline more than its answer did
        self._bare = bool(getattr(backend, "answers_in_process", False))

    @property
    def retries_inside(self) -> bool:
        """Whether the backend retries by itself (litellm's Router): then we never retry."""
        return bool(getattr(self.backend, "retries_inside", False))

    @property
    def attempt_timeout(self) -> float:
        """The timeout of one attempt: ``timeout_s``, widened for a backend that retries inside
        by its own attempts, so our timeout never cuts its retries short."""
        if self.retries_inside:
            return self.timeout_s * (1 + int(getattr(self.backend, "inner_retries", 3)))
        return self.timeout_s

    def cache_key_of(self, request: Request) -> str | None:
        """The response-cache key of ``request`` (``None`` when nothing is cached). A request
        offering tools is never cached: its answer's tool calls are more than the text the
        cache keeps."""
        if self.cache is None or request.tools:
            return None
        return cache_key(self._identity, request.content_hash(), request.run)

    async def send(self, request: Request, *, label: str = "", deadline: float | None = None) -> Response:
        """The answer to ``request``: from the cache, or from the backend with retries.

        ``deadline`` (``time.monotonic()`` seconds) bounds every attempt and wait; ``label``
        names the request in retry events. Raises :class:`InfraFailure` when no answer came.
        A fresh answer is queued for the cache (:meth:`ResponseCache.put_deferred`): whoever
        owns the cache decides when it is written.
        """
        key = self.cache_key_of(request)
        cache = self.cache  # a key exists only with a cache; naming both lets the checker see it
        if key is not None and cache is not None:
            cached = cache.get(key)
            if cached is not None:
                self.stats.cache_hits += 1
                return received(cached, self.redact_answer)  # a cache written before the key was known
        if self._start_backend and not self._running:
            await self._started(label)
        response = await self.call(request, label=label, deadline=deadline)
        if key is not None and cache is not None:
            cache.put_deferred(key, response)
        return response

    async def _started(self, label: str) -> None:
        """Wait for :meth:`Backend.start` (begun once, shared by every caller); a start that
        fails (a missing API key) fails each request that needed it, without a retry."""
        start = self._start
        if start is not None and start.done() and not start.cancelled() and start.exception() is None:
            self._running = True  # started: later requests do not wait on it (nor ask again)
            return
        if start is None:
            start = self._start = asyncio.ensure_future(self.backend.start())
        try:
            await asyncio.shield(start)
        except Exception as exc:
            raise self._failure(exc, 1, label) from exc
        self._running = True

    async def call(self, request: Request, *, label: str = "", deadline: float | None = None) -> Response:
        """One request to the backend, retried on transient failures only (never on a 4xx)."""
        policy = self.policy
        attempts = 1
        try:
            try:
                response = await self._attempt(request, deadline)
            except Exception as first:
                if policy.attempts == 1 or not is_transient(first) or self.retries_inside:
                    raise
                await self._pause(label, first, 1, deadline)

                def before_sleep(state: Any) -> None:
                    exc = state.outcome.exception()
                    self._announce(label, exc, state.attempt_number + 1, state.upcoming_sleep)

                async for attempt in AsyncRetrying(
                    stop=stop_after_attempt(policy.attempts - 1),
                    wait=lambda state: self._wait(state.outcome.exception() if state.outcome else None, state.attempt_number + 1, deadline),
                    retry=retry_if_exception(lambda exc: is_transient(exc) and not _past(deadline)),
                    before_sleep=before_sleep,
                    reraise=True,
                ):
                    with attempt:
                        attempts += 1
                        response = await self._attempt(request, deadline)
        except Exception as exc:
            self.stats.retries += attempts - 1
            raise self._failure(exc, attempts, label) from exc
        response.retries = attempts - 1
        self.stats.retries += attempts - 1
        return received(response, self.redact_answer, offered_tools=bool(request.tools))

    # -- one attempt ---------------------------------------------------------------------------
    async def _attempt(self, request: Request, deadline: float | None) -> Response:
        budget: float | None = None  # worked out only where it acts (not for a bare call without a deadline)
        if deadline is not None:
            budget = self.attempt_timeout
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no time left before the deadline ({self._limit_text(budget)})")
            budget = min(budget, left)
        self.stats.requests += 1
        if self._bare:
            t0 = time.perf_counter()
            response = await self.backend.complete(request, self.images)
            if not response.latency_s:
                response.latency_s = time.perf_counter() - t0
            return response
        if budget is None:
            budget = self.attempt_timeout
        slot = self.limiter.slot() if self.limiter is not None else contextlib.nullcontext()
        record = getattr(self.limiter, "record", None)
        async with slot:
            t0 = time.perf_counter()
            try:
                async with asyncio.timeout(budget):
                    response = await self.backend.complete(request, self.images)
            except TimeoutError as exc:
                if record is not None:
                    record(exc)
                raise TimeoutError(f"no answer within {budget:g} s ({self._limit_text(budget)})") from exc
            except Exception as exc:
                if record is not None:
                    record(exc)
                raise
            if record is not None:
                record(None)
        if not response.latency_s:
            response.latency_s = time.perf_counter() - t0
        return response

    def _limit_text(self, budget: float) -> str:
        return f"timeout {self.attempt_timeout:g} s" if budget >= self.attempt_timeout else "the caller's deadline"

    # -- between attempts ----------------------------------------------------------------------
    def _wait(self, exc: BaseException | None, failed_attempts: int, deadline: float | None) -> float:
        wait = wait_before_retry(self.policy, exc, failed_attempts)
        if deadline is not None:
            wait = max(0.0, min(wait, deadline - time.monotonic()))
        return wait

    async def _pause(self, label: str, exc: BaseException, failed_attempts: int, deadline: float | None) -> None:
        if _past(deadline):
            raise exc
        wait = self._wait(exc, failed_attempts, deadline)
        self._announce(label, exc, failed_attempts, wait)
        await asyncio.sleep(wait)

    def _announce(self, label: str, exc: BaseException, failed_attempts: int, wait: float) -> None:
        if self.on_retry is not None:
            self.on_retry(label, exc, failed_attempts, wait)

    # -- the end -------------------------------------------------------------------------------
    def _failure(self, exc: BaseException, attempts: int, label: str) -> InfraFailure:
        kind = error_type_of(exc)
        text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        message = self.redact(text + (f" (after {attempts} attempts)" if attempts > 1 else ""))
        if kind == "backend_exception" and self.on_bug is not None:
            # Not an API failure: a bug in the backend plugin; its traceback goes to the log.
            self.on_bug(label, message, self.redact(traceback.format_exc()))
        return InfraFailure(kind, message, attempts)


def _past(deadline: float | None) -> bool:
    return deadline is not None and time.monotonic() >= deadline

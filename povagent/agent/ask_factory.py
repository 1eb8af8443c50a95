"""How the agent's strategy asks the model: the ``ask`` seam and its default.

What it is for: a strategy calls ``ask(request)``; :data:`AskFactory` builds that function for
one call (the backend, the call's image store, the call's deadline). The default
(:func:`default_ask_factory`) sends through the engine's one request path, as the runner does,
with the agent's shorter retry defaults (:data:`AGENT_RETRY`); a robot app may pass its own to
add logging or a cache. What it must not do: decide retries or timeouts of its own (the engine's
rule, :mod:`povagent.engine.retry`, applies) or return anything but an answer or a
:class:`~povagent.errors.NoAnswerError`.
"""

from __future__ import annotations

import time
from typing import Callable

from povagent.config.retry_policy import RetryPolicy
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import InfraFailure, is_transient
from povagent.errors import NoAnswerError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.interfaces import Ask, Backend

#: Builds the ``ask`` a strategy calls, given the backend, the call's image store and the
#: monotonic deadline of the whole call. The default sends through the engine's one request
#: path (:class:`~povagent.engine.request_path.RequestPath`), as the runner does; a robot app
#: may pass its own (``ask_factory=``) to add logging or a cache.
AskFactory = Callable[[Backend, ImageStore, float], Ask]

#: The agent's retry defaults: a robot waits for its answer, so fewer, shorter waits than a run.
AGENT_RETRY = RetryPolicy(attempts=3, initial_wait=0.5, max_wait=8.0)


def default_ask_factory(retry: RetryPolicy, attempt_timeout_s: float | None = None) -> AskFactory:
    """An ``ask`` that sends through :class:`~povagent.engine.request_path.RequestPath`.

    Failures are classified, retried and timed exactly as in a run (timeouts, dropped
    connections, 429 and 5xx are retried; a server's Retry-After is honoured, capped; backoff
    has jitter); every attempt and wait is also cut at the call's deadline. A request that gets
    no answer becomes :class:`NoAnswerError`, its cause chained. ``attempt_timeout_s`` bounds
    one attempt (default: the time left before the deadline).
    """

    def factory(backend: Backend, images: ImageStore, deadline: float) -> Ask:
        timeout = attempt_timeout_s if attempt_timeout_s is not None else max(0.001, deadline - time.monotonic())
        path = RequestPath(backend, images, policy=retry, timeout_s=timeout)

        async def ask(request: Request) -> Response:
            try:
                return await path.send(request, label="agent", deadline=deadline)
            except InfraFailure as exc:
                if exc.error_type == "backend_exception":
                    raise NoAnswerError(f"the backend failed (a bug in it, not the model): {exc.message}") from exc.__cause__
                if not is_transient(exc.__cause__ or exc):
                    raise NoAnswerError(f"the model refused the request ({exc.error_type}): {exc.message}") from exc
                raise NoAnswerError(
                    f"no answer after {exc.attempts} attempt(s) within the deadline; last error ({exc.error_type}): {exc.message}"
                ) from exc

        return ask

    return factory

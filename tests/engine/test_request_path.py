"""The one request path: cache, limit, timeout and retries, as the runner and the agent use it."""

from __future__ import annotations

import asyncio
import time
from typing import Any

import pytest

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.config.retry_policy import RetryPolicy
from povagent.engine.cache import ResponseCache
from povagent.engine.received import valid_text
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import InfraFailure
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Message, Request, Response, TextPart
from povagent.interfaces import Backend, PermanentBackendError, TransientBackendError

FAST = RetryPolicy(attempts=3, initial_wait=0.0, max_wait=0.0)


class SemaphoreLimiter:
    """The simplest limiter a caller may hand the path: a fixed number of requests in flight."""

    def __init__(self, concurrency: int) -> None:
        self._sem = asyncio.Semaphore(concurrency)

    def slot(self):
        return self._sem


class Scripted(Backend):
    """Answers per a script: an exception to raise, a float to sleep, or a text to answer."""

    def __init__(self, *script: Any, cacheable: bool = True, retries_inside: bool = False) -> None:
        self.script = list(script)
        self.calls = 0
        self.cacheable = cacheable  # type: ignore[misc]
        self.retries_inside = retries_inside

    def identity(self):
        return {"backend": "scripted"}

    async def complete(self, request, images):
        self.calls += 1
        step = self.script.pop(0) if self.script else "fine"
        if isinstance(step, BaseException):
            raise step
        if isinstance(step, float):
            await asyncio.sleep(step)
            step = "late"
        return Response(text=step)


def request(text: str = "where is the mug?", run: int = 0) -> Request:
    spec = AnswerSpec(schema=point_answer_schema(512, 512), width=512, height=512, n_frames=1, asks_frame=False)
    return Request(messages=(Message("user", (TextPart(text),)),), answer=spec, run=run)


def path(backend, **kw) -> RequestPath:
    kw.setdefault("policy", FAST)
    kw.setdefault("timeout_s", 5.0)
    return RequestPath(backend, ImageStore(), **kw)


def send(p: RequestPath, req: Request | None = None, **kw):
    return asyncio.run(p.send(req or request(), **kw))


def test_an_answer_on_the_first_attempt_has_no_retries():
    p = path(Scripted("ok"))
    assert send(p).retries == 0 and p.stats.requests == 1


def test_transient_failures_are_retried_until_an_answer():
    backend = Scripted(TransientBackendError("503", status=503), ConnectionResetError(), "ok")
    p = path(backend)
    response = send(p)
    assert response.text == "ok" and response.retries == 2 and backend.calls == 3 and p.stats.retries == 2


def test_a_permanent_failure_is_not_retried():
    backend = Scripted(PermanentBackendError("bad image", status=400))
    with pytest.raises(InfraFailure) as info:
        send(path(backend))
    assert info.value.error_type == "bad_request" and info.value.attempts == 1 and backend.calls == 1


def test_attempts_run_out_into_a_typed_failure_that_counts_them():
    backend = Scripted(*[TransientBackendError("503", status=503)] * 5)
    with pytest.raises(InfraFailure) as info:
        send(path(backend))
    assert backend.calls == 3 and info.value.attempts == 3 and info.value.error_type == "server_error"
    assert "(after 3 attempts)" in info.value.message


def test_a_backend_that_retries_inside_gets_one_attempt():
    backend = Scripted(TransientBackendError("503", status=503), retries_inside=True)
    with pytest.raises(InfraFailure):
        send(path(backend))
    assert backend.calls == 1


def test_the_attempt_timeout_widens_for_a_backend_that_retries_inside():
    backend = Scripted(retries_inside=True)
    backend.inner_retries = 2  # type: ignore[attr-defined]
    assert path(backend, timeout_s=10).attempt_timeout == 30 and path(Scripted(), timeout_s=10).attempt_timeout == 10


def test_a_slow_attempt_is_cut_at_the_timeout_with_a_message_naming_it():
    backend = Scripted(3.0, 3.0, 3.0)
    t0 = time.monotonic()
    with pytest.raises(InfraFailure) as info:
        send(path(backend, timeout_s=0.1, policy=RetryPolicy(attempts=2, initial_wait=0, max_wait=0)))
    assert time.monotonic() - t0 < 2.0 and info.value.error_type == "timeout"
    assert "no answer within 0.1 s" in info.value.message and "timeout 0.1 s" in info.value.message


def test_the_callers_deadline_cuts_attempts_and_waits():
    backend = Scripted(TransientBackendError("429", status=429, retry_after=30.0), "ok")
    t0 = time.monotonic()
    with pytest.raises(InfraFailure):
        send(path(backend, timeout_s=30), deadline=time.monotonic() + 0.3)
    assert time.monotonic() - t0 < 2.0  # neither the 30 s Retry-After nor a 30 s attempt


def test_a_cached_answer_makes_no_call_and_a_failure_is_never_cached(tmp_path):
    cache = ResponseCache(tmp_path / "cache.sqlite")
    backend = Scripted(TransientBackendError("503", status=503), TransientBackendError("503", status=503),
                       TransientBackendError("503", status=503), "ok")  # fmt: skip
    p = path(backend, cache=cache)
    with pytest.raises(InfraFailure):
        send(p)
    assert cache.pending == 0
    assert send(p).text == "ok"
    cache.flush()
    calls = backend.calls
    again = send(p)
    assert again.text == "ok" and again.cached and backend.calls == calls and p.stats.cache_hits == 1
    cache.close()


def test_the_run_index_is_part_of_the_cache_key(tmp_path):
    with ResponseCache(tmp_path / "cache.sqlite") as cache:
        p = path(Scripted("run0", "run1"), cache=cache)
        assert send(p, request(run=0)).text == "run0"
        assert send(p, request(run=1)).text == "run1"


def test_a_backend_that_is_not_cacheable_bypasses_the_cache(tmp_path):
    with ResponseCache(tmp_path / "cache.sqlite") as cache:
        p = path(Scripted("a", "b", cacheable=False), cache=cache)
        assert [send(p).text, send(p).text] == ["a", "b"] and cache.pending == 0


def test_lone_surrogates_become_replacement_characters():
    response = send(path(Scripted('{"x": 1, "y": 2} \ud800 end')))
    assert response.text == '{"x": 1, "y": 2} \ufffd end'
    response.text.encode("utf-8")  # every answer can be written as UTF-8
    assert valid_text("plain") == "plain"


def test_a_backend_bug_is_a_backend_exception_with_its_traceback():
    bugs = []
    p = path(Scripted(RuntimeError("boom")), on_bug=lambda label, message, trace: bugs.append((label, message, trace)))
    with pytest.raises(InfraFailure) as info:
        send(p, label="k#0")
    assert info.value.error_type == "backend_exception" and info.value.attempts == 1
    (label, message, trace), = bugs
    assert label == "k#0" and "RuntimeError: boom" in message and "Traceback" in trace


def test_retries_are_announced_with_the_wait():
    seen = []
    p = path(Scripted(TransientBackendError("429", status=429, retry_after=0.01), "ok"),
             on_retry=lambda label, exc, n, wait: seen.append((label, n, wait)))  # fmt: skip
    send(p, label="k#0")
    assert seen == [("k#0", 1, 0.01)]


def test_messages_are_redacted():
    p = path(Scripted(PermanentBackendError("key sk-secret-123 rejected", status=401)),
             redact=lambda text: text.replace("sk-secret-123", "***"))  # fmt: skip
    with pytest.raises(InfraFailure) as info:
        send(p)
    assert "sk-secret-123" not in info.value.message and "***" in info.value.message


def test_the_limiter_bounds_requests_in_flight():
    in_flight, peak = 0, 0

    class Counting(Backend):
        def identity(self):
            return {}

        async def complete(self, request, images):
            nonlocal in_flight, peak
            in_flight += 1
            peak = max(peak, in_flight)
            await asyncio.sleep(0.01)
            in_flight -= 1
            return Response(text="ok")

    p = path(Counting(), limiter=SemaphoreLimiter(3))

    async def many():
        await asyncio.gather(*(p.send(request(str(i))) for i in range(12)))

    asyncio.run(many())
    assert peak == 3


def test_an_adaptive_limiter_hears_how_each_attempt_ended():
    heard = []

    class Recording(SemaphoreLimiter):
        def record(self, exc):
            heard.append(None if exc is None else type(exc).__name__)

    p = path(Scripted(TransientBackendError("429", status=429), "ok"), limiter=Recording(2))
    send(p)
    assert heard == ["TransientBackendError", None]

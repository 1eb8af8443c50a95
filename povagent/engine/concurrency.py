"""Adaptive concurrency for rate-limited APIs: how many requests may be in flight right now.

A hosted API that answers 429 ("too many requests") is telling the client to send less. The
:class:`AdaptiveConcurrency` limiter listens: every request holds a slot while in flight; a
slot released after a 429 cuts the limit by a factor (multiplicative decrease), a slot
released after an answer raises it a little (additive increase: one more slot per full
limit's worth of answers). The limit never leaves ``[1, maximum]``, where ``maximum`` is the
pipeline's ``concurrency``; a server that never says 429 therefore always sees ``maximum``
requests in flight, as with a fixed semaphore.

One congestion episode is answered once: the requests already in flight when the limit was
cut were sent at the old rate, so their 429s do not cut it again (TCP's rule of one decrease
per round trip). Without this a burst of 32 simultaneous 429s would drive the limit to 1.

Every change of the limit is logged as a ``concurrency_limit`` event (old, new, why) when a
log is given, and :attr:`AdaptiveConcurrency.limit` is there for a progress bar. This module
knows nothing about backends, rows or HTTP clients beyond "was this failure a 429": it must
not sleep, retry or time anything (the runner's retry loop waits *outside* the limiter, so a
request waiting out a Retry-After does not hold a slot).
"""

from __future__ import annotations

import asyncio
import collections
import enum
from types import TracebackType
from typing import Any, Callable, Protocol

__all__ = ["AdaptiveConcurrency", "Outcome", "Slot", "is_rate_limited"]

#: Default multiplicative decrease: the limit after a 429 is this fraction of the limit before.
DEFAULT_DECREASE = 0.7
#: Default additive increase: slots gained per full limit's worth of answered requests.
DEFAULT_INCREASE = 1.0


class EventLog(Protocol):
    """Where limit changes are reported (:class:`povagent.files.logs.RunLog` fits)."""

    def info(self, event: str, **fields: Any) -> None:
        """Record one event with its fields."""


class Outcome(enum.Enum):
    """How a request that held a slot ended, as far as the limit is concerned."""

    ANSWERED = "answered"  # the server answered: room for one more, eventually
    RATE_LIMITED = "rate_limited"  # a 429: too many in flight
    OTHER = "other"  # any other failure or a cancellation: says nothing about the rate


def is_rate_limited(exc: BaseException) -> bool:
    """Whether ``exc`` is a 429 (an HTTP status in ``status`` or ``status_code``)."""
    for attr in ("status", "status_code"):
        value = getattr(exc, attr, None)
        if isinstance(value, int) and not isinstance(value, bool):
            return value == 429
    return False


class Slot:
    """One request's place among those in flight; release it exactly once.

    As an async context manager (``async with limiter.slot():``) it is taken on entry and
    released on exit with the outcome read from the exception, if any (see
    :meth:`AdaptiveConcurrency.slot`).
    """

    __slots__ = ("_limiter", "_epoch", "_released")

    def __init__(self, limiter: AdaptiveConcurrency) -> None:
        self._limiter = limiter
        self._epoch = -1
        self._released = False

    async def __aenter__(self) -> Slot:
        self._epoch = await self._limiter._acquire()
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if exc is None:
            outcome = Outcome.ANSWERED
        elif isinstance(exc, Exception) and self._limiter.classify(exc):
            outcome = Outcome.RATE_LIMITED
        else:
            outcome = Outcome.OTHER
        self.release(outcome)

    def release(self, outcome: Outcome) -> None:
        """Give the slot back, telling the limiter how the request ended."""
        if self._released:
            raise RuntimeError("slot released twice")
        self._released = True
        self._limiter._release(self._epoch, outcome)


class AdaptiveConcurrency:
    """At most :attr:`limit` requests in flight; the limit adapts to 429s (AIMD).

    ``maximum``: the ceiling (the pipeline's ``concurrency``) and, unless ``initial`` says
    otherwise, the starting limit. ``decrease``: the factor applied on a 429 (0 < decrease < 1).
    ``increase``: slots gained per ``limit`` answered requests. ``log``: where
    ``concurrency_limit`` events go. ``classify``: which exceptions are 429s. Counters for a
    summary: ``rate_limited`` (429s seen), ``decreases`` and ``increases`` (limit changes).

    Use from one event loop::

        limiter = AdaptiveConcurrency(32, log=run_log)
        async with limiter.slot():
            response = await backend.complete(request, images)
    """

    def __init__(
        self,
        maximum: int,
        *,
        initial: int | None = None,
        decrease: float = DEFAULT_DECREASE,
        increase: float = DEFAULT_INCREASE,
        log: EventLog | None = None,
        classify: Callable[[BaseException], bool] = is_rate_limited,
    ) -> None:
        if not isinstance(maximum, int) or isinstance(maximum, bool) or maximum < 1:
            raise ValueError(f"maximum must be an integer >= 1, got {maximum!r}")
        start = maximum if initial is None else initial
        if not 1 <= start <= maximum:
            raise ValueError(f"initial must be within [1, {maximum}], got {initial!r}")
        if not 0 < decrease < 1:
            raise ValueError(f"decrease must be a factor between 0 and 1 (exclusive), got {decrease!r}")
        if not increase > 0:
            raise ValueError(f"increase must be positive, got {increase!r}")
        self.maximum = maximum
        self.decrease = decrease
        self.increase = increase
        self.log = log
        self.classify = classify
        # the limit as a real number: repeated cuts by a factor keep their fractions
        self._window = float(start)
        #: answers counted towards the next additive increase
        self._credit = 0.0
        self._in_flight = 0
        # incremented at every decrease; a slot remembers the epoch it was granted in
        self._epoch = 0
        self._waiters: collections.deque[asyncio.Future[int]] = collections.deque()
        self.decreases = 0
        self.increases = 0
        self.rate_limited = 0

    # -- what a progress bar reads -------------------------------------------------------------
    @property
    def limit(self) -> int:
        """How many requests may be in flight now (an integer in ``[1, maximum]``)."""
        return int(self._window)

    @property
    def in_flight(self) -> int:
        """How many slots are held now."""
        return self._in_flight

    @property
    def waiting(self) -> int:
        """How many callers wait for a slot."""
        return sum(1 for w in self._waiters if not w.done())

    # -- taking and giving back ----------------------------------------------------------------
    def slot(self) -> Slot:
        """A slot to hold across one request: ``async with limiter.slot(): ...``.

        On exit the slot is released as :attr:`Outcome.ANSWERED` when the block ended normally,
        :attr:`Outcome.RATE_LIMITED` when it raised an exception ``classify`` calls a 429, and
        :attr:`Outcome.OTHER` otherwise (errors and cancellation leave the limit alone).
        """
        return Slot(self)

    async def acquire(self) -> Slot:
        """Wait for a slot and return it, held; call :meth:`Slot.release` when done."""
        return await self.slot().__aenter__()

    async def _acquire(self) -> int:
        if self._in_flight < self.limit and not self._waiters:
            self._in_flight += 1
            return self._epoch
        waiter: asyncio.Future[int] = asyncio.get_running_loop().create_future()
        self._waiters.append(waiter)
        try:
            return await waiter
        except asyncio.CancelledError:
            if waiter.done() and not waiter.cancelled():
                # granted, then cancelled before running: hand the slot on
                self._in_flight -= 1
                self._wake()
            else:
                self._waiters.remove(waiter)
            raise

    def _release(self, epoch: int, outcome: Outcome) -> None:
        self._in_flight -= 1
        old = self.limit
        if outcome is Outcome.ANSWERED:
            # one more slot once a whole limit's worth of requests has been answered
            self._credit += self.increase
            while self._credit >= self.limit and self._window < self.maximum:
                self._credit -= self.limit
                self._window = min(float(self.maximum), self._window + 1.0)
            if self._window >= self.maximum:
                self._credit = 0.0
        elif outcome is Outcome.RATE_LIMITED:
            self.rate_limited += 1
            if epoch == self._epoch:  # sent after the last cut: a new congestion episode
                self._window = max(1.0, self._window * self.decrease)
                self._credit = 0.0
                self._epoch += 1
                self.decreases += 1
        new = self.limit
        if new != old:
            if new > old:
                self.increases += 1
            if self.log is not None:
                self.log.info("concurrency_limit", limit=new, previous=old, reason=outcome.value,
                              in_flight=self._in_flight, maximum=self.maximum)
        self._wake()

    def _wake(self) -> None:
        # grant slots in arrival order while the (possibly raised) limit allows
        while self._waiters and self._in_flight < self.limit:
            waiter = self._waiters.popleft()
            if waiter.done():  # cancelled while waiting
                continue
            self._in_flight += 1
            waiter.set_result(self._epoch)

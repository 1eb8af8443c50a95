"""A run's parse-and-score calls, off its event loop, in a few worker threads of the run's own.

``asyncio.to_thread`` per answer cost a run about 40 microseconds of CPU a row (a context
copied, a job handed to the default executor, two futures chained, the loop woken through its
self-pipe for every answer). A :class:`ScoreLane` keeps a worker thread waiting for the next
answer, and hands results back to the loop in batches: the loop is woken once for every answer
finished while it was busy, not once each.

What stays as it was: nothing is parsed or scored on the event loop; a call that never ends
holds its own key only (a call that has run longer than :data:`SLOW_S` makes the next answer
start another worker, up to :data:`MAX_WORKERS`, as the default executor ran several at
once); the awaiting task can be cancelled at any moment (the call's result is then dropped).
Workers are daemon threads that end after :data:`IDLE_S` without work, so a process that runs
many runs (a sweep) keeps none, and its exit never waits for one.
"""

from __future__ import annotations

import asyncio
import contextvars
import queue
import threading
import time
from typing import Any, Callable, TypeVar

_T = TypeVar("_T")

#: Worker threads at most (the default executor's on a two-core machine: min(32, cores + 4)).
MAX_WORKERS = 6
#: A call running longer than this makes the next answer start another worker.
SLOW_S = 0.05
#: A worker waits this long for another answer before it ends.
IDLE_S = 1.0


class ScoreLane:
    """Runs calls in worker threads, for the event loop that awaits them (see the module's docstring)."""

    def __init__(self) -> None:
        self._crew: _Crew | None = None

    async def call(self, fn: Callable[..., _T], *args: Any) -> _T:
        """``fn(*args)`` run in a worker thread, in a copy of the caller's context."""
        loop = asyncio.get_running_loop()
        crew = self._crew
        if crew is None or crew.loop is not loop:  # a new loop (another run) gets workers of its own
            crew = self._crew = _Crew(loop)
        future: asyncio.Future[_T] = loop.create_future()
        crew.jobs.put((future, contextvars.copy_context(), fn, args))
        crew.start_worker_if_needed()
        return await future


class _Crew:
    """The workers of one event loop, their queue of calls and the results not yet handed back."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop
        self.jobs: queue.SimpleQueue[tuple[asyncio.Future[Any], contextvars.Context, Callable[..., Any], tuple[Any, ...]]] = queue.SimpleQueue()
        self._lock = threading.Lock()
        #: when each worker started its current call (``None``: waiting for one)
        self._busy_since: dict[int, float | None] = {}
        self._next_worker = 0
        self._done: list[tuple[asyncio.Future[Any], bool, Any]] = []
        self._woken = False  # a delivery is queued on the loop already

    def start_worker_if_needed(self) -> None:
        """Start a worker when none waits for the call just queued and none has been busy long."""
        with self._lock:
            busy = self._busy_since
            if busy:
                if len(busy) >= MAX_WORKERS or any(since is None for since in busy.values()):
                    return  # a worker is waiting for this call
                if time.monotonic() - min(since for since in busy.values() if since is not None) < SLOW_S:
                    return  # every worker is busy, but none for long: one takes it next
            worker = self._next_worker
            self._next_worker += 1
            busy[worker] = None
        threading.Thread(target=self._work, args=(worker,), name=f"povagent-score-{worker}", daemon=True).start()

    def _work(self, worker: int) -> None:
        busy = self._busy_since
        while True:
            try:
                future, context, fn, args = self.jobs.get(timeout=IDLE_S)
            except queue.Empty:
                with self._lock:
                    if self.jobs.empty():
                        del busy[worker]
                        return
                continue
            busy[worker] = time.monotonic()
            try:
                done = (future, True, context.run(fn, *args))
            except BaseException as exc:  # handed to the awaiting task, not lost in this thread
                done = (future, False, exc)
            busy[worker] = None
            with self._lock:
                self._done.append(done)
                wake, self._woken = not self._woken, True
            if wake:
                try:
                    self.loop.call_soon_threadsafe(self._deliver)
                except RuntimeError:  # the loop has closed: nobody waits any more
                    pass

    def _deliver(self) -> None:
        with self._lock:
            done, self._done, self._woken = self._done, [], False
        for future, ok, value in done:
            if future.done():  # cancelled meanwhile
                continue
            if ok:
                future.set_result(value)
            else:
                future.set_exception(value)

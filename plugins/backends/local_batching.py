"""The batching queue of the in-process backend: concurrent requests generated together.

The runner sends up to ``concurrency`` requests at once; a GPU answers a batch of them in
about the time of one. :class:`BatchQueue` collects the requests waiting, groups those that
can share one ``generate`` call (the same generation settings: the group key) up to
``max_batch``, oldest first, and runs every batch on one long-lived thread of its own, so
batches never overlap (one model, one device) and the event loop keeps running meanwhile.
One thread and not a pool's next idle one: glibc gives each thread that allocates its own
malloc arena, and a generation's transient tensors left in a different arena per batch held
the process at about 1.8x a plain script's memory.

A batch that runs out of memory is split in halves, each run again, down to single requests;
a single request that still does not fit fails with :class:`LocalOutOfMemory`, which the
backend turns into a permanent, typed failure (no retry: the same request would fail again).

This module knows nothing of models: it runs the function it is given.
"""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Generic, Hashable, TypeVar

Item = TypeVar("Item")
Result = TypeVar("Result")


class LocalOutOfMemory(Exception):
    """The device ran out of memory for a batch (or a single request)."""


@dataclass
class _Waiting(Generic[Item, Result]):
    item: Item
    group: Hashable
    future: asyncio.Future[Result] = field(repr=False)


@dataclass
class BatchStats:
    """What the queue did: batches run, their sizes, splits after running out of memory."""

    batches: int = 0
    requests: int = 0
    largest: int = 0
    splits: int = 0


class BatchQueue(Generic[Item, Result]):
    """Groups waiting items by key into batches of at most ``max_batch`` for ``run_batch``.

    ``run_batch(items)`` returns one result per item, in order, or raises
    :class:`LocalOutOfMemory`; it runs on the queue's own thread (named ``povagent-generate``),
    the same one for every batch until :meth:`aclose`. Any other exception fails every item of
    that batch with it.
    """

    def __init__(self, run_batch: Callable[[list[Item]], list[Result]], max_batch: int) -> None:
        if max_batch < 1:
            raise ValueError("max_batch must be at least 1")
        self._run_batch = run_batch
        self.max_batch = max_batch
        self._waiting: list[_Waiting[Item, Result]] = []
        self._wake: asyncio.Event | None = None
        self._worker: asyncio.Task[None] | None = None
        self._thread: ThreadPoolExecutor | None = None
        self.stats = BatchStats()

    async def submit(self, item: Item, group: Hashable = None) -> Result:
        """Queue ``item`` and wait for its result (batched with others of the same ``group``)."""
        loop = asyncio.get_running_loop()
        waiting: _Waiting[Item, Result] = _Waiting(item, group, loop.create_future())
        self._waiting.append(waiting)
        if self._worker is None or self._worker.done():
            self._wake = asyncio.Event()
            self._worker = loop.create_task(self._serve())
        assert self._wake is not None
        self._wake.set()
        return await waiting.future

    def _next_batch(self) -> list[_Waiting[Item, Result]]:
        # requests whose caller gave up (a timeout) are dropped, never generated
        self._waiting = [w for w in self._waiting if not w.future.done()]
        if not self._waiting:
            return []
        group = self._waiting[0].group
        batch = [w for w in self._waiting if w.group == group][: self.max_batch]
        chosen = {id(w) for w in batch}
        self._waiting = [w for w in self._waiting if id(w) not in chosen]
        return batch

    async def _serve(self) -> None:
        assert self._wake is not None
        while True:
            await self._wake.wait()
            self._wake.clear()
            # one turn of the loop lets requests sent at the same moment join the batch
            await asyncio.sleep(0)
            while batch := self._next_batch():
                await self._run(batch)
            if not self._waiting:
                return

    async def _run(self, batch: list[_Waiting[Item, Result]]) -> None:
        try:
            if self._thread is None:
                self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="povagent-generate")
            items = [w.item for w in batch]
            results = await asyncio.get_running_loop().run_in_executor(self._thread, self._run_batch, items)
        except LocalOutOfMemory as exc:
            if len(batch) == 1:
                _fail(batch, exc)
                return
            self.stats.splits += 1
            half = len(batch) // 2
            await self._run(batch[:half])
            await self._run(batch[half:])
            return
        except BaseException as exc:  # the batch's failure is each of its requests' failure
            _fail(batch, exc)
            if not isinstance(exc, Exception):
                raise
            return
        self.stats.batches += 1
        self.stats.requests += len(batch)
        self.stats.largest = max(self.stats.largest, len(batch))
        if len(results) != len(batch):
            _fail(batch, RuntimeError(f"a batch of {len(batch)} returned {len(results)} results"))
            return
        for waiting, result in zip(batch, results):
            if not waiting.future.done():
                waiting.future.set_result(result)

    async def aclose(self) -> None:
        """Stop the worker; requests still waiting fail with :class:`asyncio.CancelledError`."""
        for waiting in self._waiting:
            if not waiting.future.done():
                waiting.future.cancel()
        self._waiting = []
        if self._worker is not None and not self._worker.done():
            self._worker.cancel()
            try:
                await self._worker
            except asyncio.CancelledError:
                pass
        self._worker = None
        if self._thread is not None:
            # a batch still generating finishes on its thread; nothing waits for it
            thread, self._thread = self._thread, None
            thread.shutdown(wait=False, cancel_futures=True)


def _fail(batch: list[Any], exc: BaseException) -> None:
    for waiting in batch:
        if not waiting.future.done():
            waiting.future.set_exception(exc)

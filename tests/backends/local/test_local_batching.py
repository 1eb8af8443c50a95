"""The batching queue: waiting requests grouped up to max_batch, split when memory runs out."""

from __future__ import annotations

import asyncio

import pytest

from povagent_plugins.backends.local_batching import BatchQueue, LocalOutOfMemory


def run(queue: BatchQueue, items: list, groups: list | None = None) -> list:
    async def go() -> list:
        try:
            return await asyncio.gather(*(queue.submit(i, g) for i, g in zip(items, groups or [None] * len(items))), return_exceptions=True)
        finally:
            await queue.aclose()

    return asyncio.run(go())


def test_waiting_requests_are_grouped_up_to_max_batch():
    seen: list[list[int]] = []
    queue = BatchQueue(lambda items: seen.append(items) or [i * 10 for i in items], max_batch=3)
    assert run(queue, [1, 2, 3, 4, 5]) == [10, 20, 30, 40, 50]
    assert seen == [[1, 2, 3], [4, 5]]


def test_only_requests_of_one_group_share_a_batch():
    seen: list[list[int]] = []
    queue = BatchQueue(lambda items: seen.append(items) or items, max_batch=8)
    run(queue, [1, 2, 3, 4], ["short", "long", "short", "long"])
    assert seen == [[1, 3], [2, 4]]


def test_a_batch_out_of_memory_is_split_and_retried_in_halves():
    seen: list[list[int]] = []

    def fits_two(items: list[int]) -> list[int]:
        seen.append(items)
        if len(items) > 2:
            raise LocalOutOfMemory("too many")
        return items

    queue = BatchQueue(fits_two, max_batch=8)
    assert run(queue, [1, 2, 3, 4, 5]) == [1, 2, 3, 4, 5]
    assert seen[0] == [1, 2, 3, 4, 5] and [1, 2] in seen and queue.stats.splits >= 2 and queue.stats.largest == 2


def test_a_single_request_out_of_memory_fails_alone():
    def never_three(items: list[int]) -> list[int]:
        if 3 in items:
            raise LocalOutOfMemory("request 3 does not fit")
        return items

    results = run(BatchQueue(never_three, max_batch=4), [1, 2, 3, 4])
    assert results[:2] == [1, 2] and results[3] == 4
    assert isinstance(results[2], LocalOutOfMemory)


def test_any_other_failure_fails_the_whole_batch_without_a_split():
    calls = []

    def broken(items: list[int]) -> list[int]:
        calls.append(items)
        raise ValueError("processor refused the batch")

    results = run(BatchQueue(broken, max_batch=4), [1, 2])
    assert calls == [[1, 2]] and all(isinstance(r, ValueError) for r in results)


def test_max_batch_must_be_positive():
    with pytest.raises(ValueError):
        BatchQueue(lambda items: items, max_batch=0)


def test_every_batch_runs_on_the_queues_one_thread_while_other_work_uses_the_pool():
    """One generation thread, not the pool's next idle one: each thread that allocates gets
    its own malloc arena, and a batch per arena held memory at 1.8x a plain script's."""
    import threading
    import time

    threads: list[tuple[int, str]] = []

    def record_thread(items: list[int]) -> list[int]:
        threads.append((threading.get_ident(), threading.current_thread().name))
        time.sleep(0.01)
        return items

    queue = BatchQueue(record_thread, max_batch=2)

    async def go() -> None:
        try:
            for i in range(4):  # batch after batch, with the default pool busy beside each
                await asyncio.gather(queue.submit(i), asyncio.to_thread(time.sleep, 0.02), asyncio.to_thread(time.sleep, 0.02))
        finally:
            await queue.aclose()

    asyncio.run(go())
    assert len(threads) == 4 and len(set(threads)) == 1
    assert threads[0][1].startswith("povagent-generate")

"""Adaptive concurrency (povagent/engine/concurrency.py): AIMD on 429s, bounded by ``concurrency``."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from povagent.engine.concurrency import AdaptiveConcurrency, Outcome, is_rate_limited
from povagent.interfaces import PermanentBackendError, TransientBackendError

pytestmark = pytest.mark.timeout(20)


class Events:
    """A log that keeps what it is told (the RunLog interface: ``info(event, **fields)``)."""

    def __init__(self) -> None:
        self.events: list[tuple[str, dict[str, Any]]] = []

    def info(self, event: str, **fields: Any) -> None:
        self.events.append((event, fields))


def rate_limit() -> TransientBackendError:
    return TransientBackendError("429 Too Many Requests", status=429)


async def hold(limiter: AdaptiveConcurrency, n: int):
    """Take ``n`` slots (each at once available) and return them held."""
    return [await limiter.acquire() for _ in range(n)]


def run(coro):
    return asyncio.run(coro)


# -- bounds -------------------------------------------------------------------------------------
def test_starts_at_the_maximum_so_an_api_without_429s_sees_full_concurrency():
    assert AdaptiveConcurrency(16).limit == 16


def test_answers_never_raise_the_limit_above_the_maximum():
    async def main():
        limiter = AdaptiveConcurrency(4, initial=3)
        for _ in range(200):
            (await limiter.acquire()).release(Outcome.ANSWERED)
        return limiter.limit

    assert run(main()) == 4


def test_never_more_requests_in_flight_than_the_limit():
    async def main():
        limiter = AdaptiveConcurrency(5)
        peak = 0

        async def request():
            nonlocal peak
            async with limiter.slot():
                peak = max(peak, limiter.in_flight)
                await asyncio.sleep(0.001)

        await asyncio.gather(*(request() for _ in range(100)))
        return peak, limiter.in_flight

    assert run(main()) == (5, 0)


def test_repeated_429s_never_take_the_limit_below_one():
    async def main():
        limiter = AdaptiveConcurrency(8, decrease=0.5)
        for _ in range(20):
            (await limiter.acquire()).release(Outcome.RATE_LIMITED)
        return limiter.limit

    assert run(main()) == 1


def test_one_slot_still_flows_at_limit_one():
    async def main():
        limiter = AdaptiveConcurrency(8, initial=1)
        done = 0

        async def request():
            nonlocal done
            async with limiter.slot():
                await asyncio.sleep(0)
            done += 1

        await asyncio.gather(*(request() for _ in range(10)))
        return done

    assert run(main()) == 10


# -- multiplicative decrease --------------------------------------------------------------------
def test_a_429_cuts_the_limit_by_the_decrease_factor():
    async def main():
        limiter = AdaptiveConcurrency(32, decrease=0.5)
        (await limiter.acquire()).release(Outcome.RATE_LIMITED)
        return limiter.limit

    assert run(main()) == 16


def test_429s_of_requests_sent_before_the_cut_do_not_cut_again():
    # 32 requests in flight all answered 429: one congestion episode, one cut (not 0.5**32)
    async def main():
        limiter = AdaptiveConcurrency(32, decrease=0.5)
        slots = await hold(limiter, 32)
        for s in slots:
            s.release(Outcome.RATE_LIMITED)
        return limiter.limit, limiter.decreases, limiter.rate_limited

    assert run(main()) == (16, 1, 32)


def test_a_429_of_a_request_sent_after_the_cut_cuts_again():
    async def main():
        limiter = AdaptiveConcurrency(32, decrease=0.5)
        early = await hold(limiter, 2)
        early[0].release(Outcome.RATE_LIMITED)  # 32 -> 16
        late = await limiter.acquire()  # sent at the new limit
        early[1].release(Outcome.RATE_LIMITED)  # old episode: ignored
        late.release(Outcome.RATE_LIMITED)  # new episode: 16 -> 8
        return limiter.limit

    assert run(main()) == 8


def test_after_a_cut_no_new_request_starts_until_in_flight_falls_below_the_limit():
    async def main():
        limiter = AdaptiveConcurrency(4, decrease=0.5)
        slots = await hold(limiter, 4)
        slots[0].release(Outcome.RATE_LIMITED)  # limit 2, 3 still in flight
        waiter = asyncio.create_task(limiter.acquire())
        await asyncio.sleep(0.01)
        blocked_at_3 = not waiter.done()
        slots[1].release(Outcome.OTHER)  # 2 in flight: still at the limit
        await asyncio.sleep(0.01)
        blocked_at_2 = not waiter.done()
        slots[2].release(Outcome.OTHER)  # 1 in flight: room for one
        await asyncio.sleep(0.01)
        granted = waiter.done()
        return blocked_at_3, blocked_at_2, granted, limiter.in_flight

    assert run(main()) == (True, True, True, 2)


# -- additive increase --------------------------------------------------------------------------
def test_a_full_limit_of_answers_raises_the_limit_by_one():
    async def main():
        limiter = AdaptiveConcurrency(10, initial=4)
        seen = []
        for _ in range(4):
            (await limiter.acquire()).release(Outcome.ANSWERED)
            seen.append(limiter.limit)
        return seen

    # 1/4 of a slot per answer: the fourth answer completes the slot
    assert run(main()) == [4, 4, 4, 5]


def test_the_increase_option_scales_the_growth():
    async def main():
        limiter = AdaptiveConcurrency(10, initial=4, increase=2.0)
        for _ in range(2):
            (await limiter.acquire()).release(Outcome.ANSWERED)
        return limiter.limit

    assert run(main()) == 5


def test_a_raised_limit_wakes_waiting_requests():
    async def main():
        limiter = AdaptiveConcurrency(3, initial=1)
        first = await limiter.acquire()
        waiters = [asyncio.create_task(limiter.acquire()) for _ in range(2)]
        await asyncio.sleep(0.01)
        waiting_before = sum(not w.done() for w in waiters)
        first.release(Outcome.ANSWERED)  # 1 -> 2: room for both waiters at once
        await asyncio.sleep(0.01)
        return waiting_before, sum(w.done() for w in waiters), limiter.in_flight

    assert run(main()) == (2, 2, 2)


def test_the_limit_recovers_to_the_maximum_after_the_429s_stop():
    async def main():
        limiter = AdaptiveConcurrency(8, decrease=0.5)
        (await limiter.acquire()).release(Outcome.RATE_LIMITED)
        low = limiter.limit
        for _ in range(100):
            (await limiter.acquire()).release(Outcome.ANSWERED)
        return low, limiter.limit

    assert run(main()) == (4, 8)


# -- neutral outcomes ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "exc",
    [TransientBackendError("500 server error", status=500), PermanentBackendError("400 bad request", status=400), TimeoutError()],
    ids=["500", "400", "timeout"],
)
def test_other_failures_leave_the_limit_alone_and_free_the_slot(exc):
    async def main():
        limiter = AdaptiveConcurrency(6, initial=5)
        with pytest.raises(type(exc)):
            async with limiter.slot():
                raise exc
        return limiter.limit, limiter.in_flight

    assert run(main()) == (5, 0)


def test_the_slot_context_reads_a_429_from_the_exception_and_reraises_it():
    async def main():
        limiter = AdaptiveConcurrency(10, decrease=0.5)
        with pytest.raises(TransientBackendError):
            async with limiter.slot():
                raise rate_limit()
        return limiter.limit

    assert run(main()) == 5


def test_the_slot_context_counts_a_normal_exit_as_answered():
    async def main():
        limiter = AdaptiveConcurrency(10, initial=1)
        async with limiter.slot():
            pass
        return limiter.limit

    assert run(main()) == 2


def test_a_cancelled_request_frees_its_slot_without_changing_the_limit():
    async def main():
        limiter = AdaptiveConcurrency(2)
        started = asyncio.Event()

        async def request():
            async with limiter.slot():
                started.set()
                await asyncio.sleep(10)

        task = asyncio.create_task(request())
        await started.wait()
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        return limiter.limit, limiter.in_flight

    assert run(main()) == (2, 0)


def test_a_waiter_cancelled_while_waiting_takes_no_slot():
    async def main():
        limiter = AdaptiveConcurrency(1)
        held = await limiter.acquire()
        waiter = asyncio.create_task(limiter.acquire())
        await asyncio.sleep(0.01)
        waiter.cancel()
        with pytest.raises(asyncio.CancelledError):
            await waiter
        held.release(Outcome.ANSWERED)
        after = await asyncio.wait_for(limiter.acquire(), 1)
        return limiter.in_flight, limiter.waiting, after is not None

    assert run(main()) == (1, 0, True)


def test_a_waiter_cancelled_after_being_granted_hands_the_slot_on():
    async def main():
        limiter = AdaptiveConcurrency(1)
        held = await limiter.acquire()
        first = asyncio.create_task(limiter.acquire())
        second = asyncio.create_task(limiter.acquire())
        await asyncio.sleep(0.01)
        held.release(Outcome.OTHER)  # grants `first`, which is cancelled before it runs
        first.cancel()
        with pytest.raises(asyncio.CancelledError):
            await first
        slot = await asyncio.wait_for(second, 1)
        return limiter.in_flight, slot is not None

    assert run(main()) == (1, True)


def test_waiters_are_served_in_arrival_order():
    async def main():
        limiter = AdaptiveConcurrency(1)
        order: list[int] = []
        held = await limiter.acquire()

        async def request(i: int):
            async with limiter.slot():
                order.append(i)

        tasks = [asyncio.create_task(request(i)) for i in range(5)]
        await asyncio.sleep(0.01)
        held.release(Outcome.OTHER)
        await asyncio.gather(*tasks)
        return order

    assert run(main()) == [0, 1, 2, 3, 4]


def test_a_slot_released_twice_is_a_bug():
    async def main():
        limiter = AdaptiveConcurrency(2)
        slot = await limiter.acquire()
        slot.release(Outcome.ANSWERED)
        with pytest.raises(RuntimeError, match="twice"):
            slot.release(Outcome.ANSWERED)
        return limiter.in_flight

    assert run(main()) == 0


# -- the log ------------------------------------------------------------------------------------
def test_every_change_of_the_limit_is_logged_with_old_new_and_reason():
    async def main():
        log = Events()
        limiter = AdaptiveConcurrency(4, decrease=0.5, log=log)
        (await limiter.acquire()).release(Outcome.RATE_LIMITED)  # 4 -> 2
        for _ in range(2):
            (await limiter.acquire()).release(Outcome.ANSWERED)  # 2 -> 3 on the second
        return log.events

    events = run(main())
    assert events == [
        ("concurrency_limit", {"limit": 2, "previous": 4, "reason": "rate_limited", "in_flight": 0, "maximum": 4}),
        ("concurrency_limit", {"limit": 3, "previous": 2, "reason": "answered", "in_flight": 0, "maximum": 4}),
    ]


def test_nothing_is_logged_while_the_limit_stays_put():
    async def main():
        log = Events()
        limiter = AdaptiveConcurrency(4, log=log)
        for _ in range(10):
            (await limiter.acquire()).release(Outcome.ANSWERED)  # already at the maximum
            (await limiter.acquire()).release(Outcome.OTHER)
        return log.events

    assert run(main()) == []


# -- classification and arguments ---------------------------------------------------------------
def test_is_rate_limited_reads_status_or_status_code():
    class LibraryError(Exception):
        status_code = 429

    assert is_rate_limited(TransientBackendError("x", status=429))
    assert is_rate_limited(LibraryError())
    assert not is_rate_limited(TransientBackendError("x", status=503))
    assert not is_rate_limited(TransientBackendError("no status"))
    assert not is_rate_limited(ValueError("429 in the text is not a status"))


@pytest.mark.timeout(90)  # the first litellm import takes seconds, more on a loaded machine
def test_litellm_rate_limit_errors_count_as_429():
    from povagent.engine.llm_import import import_litellm

    litellm = import_litellm()
    exc = litellm.RateLimitError("slow down", llm_provider="openai", model="m")
    assert is_rate_limited(exc)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"maximum": 0}, "maximum"),
        ({"maximum": 4, "initial": 5}, "initial"),
        ({"maximum": 4, "initial": 0}, "initial"),
        ({"maximum": 4, "decrease": 1.0}, "decrease"),
        ({"maximum": 4, "decrease": 0.0}, "decrease"),
        ({"maximum": 4, "increase": 0.0}, "increase"),
    ],
)
def test_bad_settings_are_refused_with_the_setting_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        AdaptiveConcurrency(**kwargs)

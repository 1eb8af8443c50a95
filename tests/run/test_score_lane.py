"""A run's parse-and-score calls run in worker threads of its own, never on the event loop; a
slow call holds its own key only; a failure reaches the awaiting task; idle workers end."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

from povagent.run import score_lane
from povagent.run.score_lane import ScoreLane

pytestmark = pytest.mark.timeout(60)


def _where() -> tuple[str, bool]:
    try:
        asyncio.get_running_loop()
        on_loop = True
    except RuntimeError:
        on_loop = False
    return threading.current_thread().name, on_loop


def test_every_call_runs_in_a_worker_thread_and_returns_its_result_in_order():
    async def main():
        lane = ScoreLane()
        return await asyncio.gather(*(lane.call(lambda i=i: (i, *_where())) for i in range(200)))

    got = asyncio.run(main())
    assert [i for i, _, _ in got] == list(range(200))
    assert all(name.startswith("povagent-score-") and not on_loop for _, name, on_loop in got)


def test_an_exception_reaches_the_awaiting_task():
    def fail(text):
        raise ValueError(text)

    async def main():
        return await ScoreLane().call(fail, "bad reply")

    with pytest.raises(ValueError, match="bad reply"):
        asyncio.run(main())


def test_a_call_that_does_not_end_holds_its_own_key_only():
    release = threading.Event()

    async def main():
        lane = ScoreLane()
        stuck = asyncio.ensure_future(lane.call(release.wait, 30))
        await asyncio.sleep(2 * score_lane.SLOW_S)  # the first worker is busy, and has been for long
        t0 = time.monotonic()
        quick = await asyncio.wait_for(lane.call(lambda: "scored"), timeout=5)
        waited = time.monotonic() - t0
        release.set()
        await stuck
        return quick, waited

    quick, waited = asyncio.run(main())
    assert quick == "scored" and waited < 5


def test_a_cancelled_wait_drops_the_result_and_the_lane_goes_on():
    async def main():
        lane = ScoreLane()
        slow = asyncio.ensure_future(lane.call(time.sleep, 0.2))
        await asyncio.sleep(0.01)
        slow.cancel()
        with pytest.raises(asyncio.CancelledError):
            await slow
        return await lane.call(lambda: "next")

    assert asyncio.run(main()) == "next"


def test_idle_workers_end(monkeypatch):
    monkeypatch.setattr(score_lane, "IDLE_S", 0.05)

    async def main():
        lane = ScoreLane()
        await asyncio.gather(*(lane.call(lambda: None) for _ in range(20)))

    asyncio.run(main())
    deadline = time.monotonic() + 5
    while any(t.name.startswith("povagent-score-") for t in threading.enumerate()) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not any(t.name.startswith("povagent-score-") for t in threading.enumerate())


def test_a_lane_used_by_a_second_loop_answers_there():
    lane = ScoreLane()

    async def once(value):
        return await lane.call(lambda: value)

    assert asyncio.run(once(1)) == 1
    assert asyncio.run(once(2)) == 2

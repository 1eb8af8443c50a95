"""Blocking work a stop must never wait for: run in a daemon thread of its own, awaited as a future.

``asyncio.to_thread`` runs work in the event loop's default executor, whose threads are joined
when the loop shuts down and again when the interpreter exits. Work that may never end (an
import of a large library, a checkpoint's loading, which runs its own code and reads files
someone else made) would then hold a cancelled run forever: a SIGTERM or a Ctrl-C cancels the
task awaiting it, and the process still cannot end. :func:`in_daemon_thread` starts a daemon
thread per call instead: the awaiting task can be cancelled at any moment, the thread's result
is dropped if nobody waits any more, and the interpreter's exit does not join it.

For work that ends (a generate call, a file read) the default executor is the right tool.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Callable, TypeVar

_T = TypeVar("_T")


def in_daemon_thread(fn: Callable[[], _T], name: str) -> asyncio.Future[_T]:
    """A future of ``fn()`` run in a new daemon thread named ``name`` (call from the event loop)."""
    loop = asyncio.get_running_loop()
    future: asyncio.Future[_T] = loop.create_future()

    def settle(ok: bool, value: object) -> None:
        if future.done():  # cancelled or timed out meanwhile
            return
        if ok:
            future.set_result(value)  # type: ignore[arg-type]  # fn's own result
        else:
            future.set_exception(value)  # type: ignore[arg-type]  # the exception fn raised

    def work() -> None:
        try:
            result: object = fn()
            ok = True
        except BaseException as exc:  # handed to the waiting task, not lost in this thread
            result, ok = exc, False
        try:
            loop.call_soon_threadsafe(settle, ok, result)
        except RuntimeError:  # the loop has closed: nobody waits any more
            pass

    threading.Thread(target=work, name=name, daemon=True).start()
    return future

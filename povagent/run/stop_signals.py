"""SIGTERM stops a run the way Ctrl-C does: cleanly, rows kept, the summary marked interrupted;
SIGINT stops it even where it was inherited ignored (a job a script started in the background).

Schedulers (Slurm, Kubernetes, systemd) and ``timeout`` stop a job with SIGTERM; Python's
default for it is to die at once, with no message and no summary. Inside
:func:`sigterm_as_interrupt` a SIGTERM takes the path of SIGINT instead: the handler Python (or
``asyncio.run``, which cancels the running task so every ``finally`` runs) has for SIGINT at that
moment is called, so the runner drains its journal, writes ``summary.json`` with
``"interrupted": true`` and the command says how to resume. The returned state records that it
was a SIGTERM, so the command can exit with 143 (128 + 15, what a scheduler expects of a job it
terminated) instead of Ctrl-C's 130.

Only the command line installs this (an application embedding the runner keeps its own signal
policy); it does nothing outside the main thread, where Python allows no signal handler.

Where the stop lands: a SIGTERM must never raise in the middle of whatever code is running.
``asyncio.run`` turns SIGINT into a cancellation of its main task, which arrives at an ``await``;
but it installs that handler only when SIGINT has Python's default handler, and a job started
in the background by a script (``cmd &``) inherits SIGINT *ignored*. Raising KeyboardInterrupt
from the handler there can land between a run's last row and its ``summary.json`` (the summary
is then never written). So the runner's coroutines mark the task a stop cancels
(:func:`cancelled_on_stop`), and a SIGTERM cancels that task, whatever SIGINT's disposition;
the cancellation that comes out of ``asyncio.run`` is turned back into KeyboardInterrupt here.
A second SIGTERM stops at once, as a second Ctrl-C does.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import threading
from dataclasses import dataclass
from types import FrameType
from typing import Awaitable, Iterator

#: Exit codes of a run stopped by a signal (documented in the README's reliability section).
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT)
EXIT_TERMINATED = 143  # SIGTERM

#: Tasks a stop cancels, innermost last (see :func:`cancelled_on_stop`).
_STOPPABLE: list[asyncio.Task[object]] = []


@dataclass
class StopRequest:
    """Which signal stopped the run, if one did."""

    terminated: bool = False

    @property
    def exit_code(self) -> int:
        """143 after a SIGTERM, 130 after Ctrl-C."""
        return EXIT_TERMINATED if self.terminated else EXIT_INTERRUPTED

    @property
    def what(self) -> str:
        """``terminated (SIGTERM)`` or ``interrupted``, for the one-line message."""
        return "terminated (SIGTERM)" if self.terminated else "interrupted"


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[StopRequest]:
    """While the block runs, SIGTERM is handled as SIGINT is; the previous handler comes back after."""
    state = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield state
        return

    def on_sigterm(signum: int, frame: FrameType | None) -> None:
        first = not state.terminated
        state.terminated = True
        task = next((t for t in reversed(_STOPPABLE) if not t.done()), None)
        if first and task is not None:
            # what asyncio.run does with a first Ctrl-C: the stop arrives at the task's next await
            task.cancel()
            task.get_loop().call_soon_threadsafe(lambda: None)  # wake a loop asleep in select()
            return
        handler = signal.getsignal(signal.SIGINT)
        if callable(handler) and first:
            handler(signal.SIGINT, frame)  # asyncio.run's: cancel the main task; Python's: KeyboardInterrupt
        else:  # a second SIGTERM, or SIGINT ignored and no run under way: stop now
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, on_sigterm)
    # a command started in the background by a script (``cmd &``, ``nohup cmd &``) inherits
    # SIGINT ignored, and Python keeps it so: a ``kill -INT`` would then do nothing. A run is
    # stopped by SIGINT wherever it was started, as Ctrl-C stops it in a terminal.
    ignored = signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    if ignored:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield state
    except asyncio.CancelledError:
        if not state.terminated:
            raise
        # the run's task was cancelled by the SIGTERM, not by asyncio's SIGINT handler, so
        # asyncio.run hands the cancellation on as it is: it is the same stop as Ctrl-C's
        raise KeyboardInterrupt from None
    finally:
        signal.signal(signal.SIGTERM, previous)
        if ignored:
            signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def cancelled_on_stop() -> Iterator[None]:
    """Inside a coroutine: while the block runs, a SIGTERM (under :func:`sigterm_as_interrupt`)
    cancels the current task, so the stop arrives at an ``await`` and every ``finally`` runs
    whole. Harmless where no handler is installed (a library call, a cluster worker)."""
    task = asyncio.current_task()
    if task is None:
        yield
        return
    _STOPPABLE.append(task)
    try:
        yield
    finally:
        _STOPPABLE.remove(task)


async def finish_through_stop(closing: Awaitable[None]) -> bool:
    """Await ``closing`` to its end even if this task is cancelled meanwhile; say whether it was.

    Closing the journal and the backend must finish for the run folder to be whole (a journal
    left mid-batch loses rows, a summary never written loses the run's account), so a stop
    arriving during them is held and reported to the caller, which raises it once done.
    """
    inner = asyncio.ensure_future(closing)
    stop_came = False
    while not inner.done():
        try:
            await asyncio.shield(inner)
        except asyncio.CancelledError:
            stop_came = True
            if inner.cancelled():  # the loop is shutting down and cancelled it too
                return True
    inner.result()
    return stop_came


def stop_requested() -> bool:
    """Whether the current task has been asked to stop (a cancellation requested, delivered or
    not yet); False outside a task."""
    task = asyncio.current_task() if _loop_running() else None
    return task is not None and task.cancelling() > 0


def _loop_running() -> bool:
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return False
    return True

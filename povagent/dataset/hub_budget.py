"""One Hub download's budget: its deadline, its stop flag, the files it is writing, and the
threads that work within it.

:class:`Budget` is shared by every thread of a download (:mod:`povagent.dataset.hub_transfer`);
at the deadline or on Ctrl-C it is abandoned: the stop flag is set and every file still being
written is removed, so nothing unfinished is kept. :func:`run_parallel` and
:func:`with_deadline` run work inside it.
"""

from __future__ import annotations

import os
import queue
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, TypeVar

from povagent.dataset.hub_limits import DownloadLimits
from povagent.errors import DatasetError

#: Files fetched at once (huggingface_hub's default too).
WORKERS = 8
#: Longest wait for one network read, below the deadline.
READ_TIMEOUT_S = 30.0

T = TypeVar("T")


class DeadlinePassed(DatasetError):
    """The download's deadline passed (or it was stopped); nothing unfinished was kept."""


@dataclass
class Budget:
    """The deadline and the stop flag one download shares between its threads."""

    limits: DownloadLimits
    started: float = field(default_factory=time.monotonic)
    stop: threading.Event = field(default_factory=threading.Event)
    fetched_files: int = 0
    fetched_bytes: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)
    #: Files being written (``*.incomplete``), removed by :meth:`abandon` at the deadline.
    unfinished: set[str] = field(default_factory=set)
    #: Called by :meth:`abandon` (e.g. to end a progress bar's line before the error is printed).
    on_abandon: list[Callable[[], Any]] = field(default_factory=list)

    @property
    def deadline(self) -> float:
        """The monotonic time the download must end by."""
        return self.started + self.limits.deadline_s

    def remaining(self) -> float:
        """Seconds left (0 once passed)."""
        return max(0.0, self.deadline - time.monotonic())

    def timeout(self) -> float:
        """A network timeout that ends no later than the deadline."""
        return max(0.05, min(READ_TIMEOUT_S, self.remaining()))

    def check(self) -> None:
        """Raise :class:`DeadlinePassed` once the deadline passed or the download was stopped."""
        if self.stop.is_set() or time.monotonic() >= self.deadline:
            self.stop.set()
            raise DeadlinePassed("deadline passed")

    def create_unfinished(self, path: str) -> Any:
        """Open a new ``*.incomplete`` file for writing, unless the download was stopped.

        Created and recorded under the lock :meth:`abandon` takes, so no such file appears
        after the download was given up.
        """
        with self.lock:
            self.check()
            handle = open(path, "xb")  # noqa: SIM115 - the caller closes it
            self.unfinished.add(path)
            return handle

    def finish(self, path: str) -> None:
        """Forget an ``*.incomplete`` file (renamed into place, or removed), removing it if still there."""
        with self.lock:
            self.unfinished.discard(path)
            if os.path.lexists(path):
                os.unlink(path)

    def abandon(self) -> None:
        """Stop the download and remove every file still being written (from the caller's thread,
        at the deadline: a worker stuck in a read may outlive the process)."""
        with self.lock:
            self.stop.set()
            for path in self.unfinished:
                try:
                    os.unlink(path)
                except OSError:
                    pass
            self.unfinished.clear()
        for call in self.on_abandon:
            call()

    def count(self, files: int = 0, size: int = 0) -> None:
        """Add to what was fetched (for the messages)."""
        with self.lock:
            self.fetched_files += files
            self.fetched_bytes += size


def run_parallel(work: Callable[[T], None], items: list[T], budget: Budget, workers: int = WORKERS) -> None:
    """Run ``work`` on every item in daemon threads; the first error stops the rest and is raised."""
    todo: queue.Queue[T] = queue.Queue()
    for item in items:
        todo.put(item)
    errors: list[BaseException] = []

    def worker() -> None:
        while not budget.stop.is_set():
            try:
                item = todo.get_nowait()
            except queue.Empty:
                return
            try:
                work(item)
            except BaseException as exc:
                if not errors:
                    errors.append(exc)
                budget.stop.set()
                return

    threads = [threading.Thread(target=worker, daemon=True, name=f"hub-fetch-{i}") for i in range(min(workers, len(items)))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]
    budget.check()


def with_deadline(fn: Callable[[], T], budget: Budget) -> T:
    """``fn()`` in a daemon thread, given up on at the budget's deadline.

    At the deadline (or on Ctrl-C) the budget is abandoned: its stop flag is set and the files
    still being written are removed, so the threads (left to end on their own) write nothing
    more that anyone trusts: a blob is only named once its bytes are complete and checked, under
    the lock that abandoning takes. Raises :class:`DeadlinePassed` at the deadline.
    """
    result: list[T] = []
    errors: list[BaseException] = []

    def run() -> None:
        try:
            result.append(fn())
        except BaseException as exc:
            errors.append(exc)

    thread = threading.Thread(target=run, daemon=True, name="hub-download")
    thread.start()
    try:
        thread.join(budget.remaining() + 0.05)
    except KeyboardInterrupt:
        budget.abandon()
        raise
    if thread.is_alive():
        budget.abandon()
        raise DeadlinePassed("deadline passed")
    if errors:
        raise errors[0]
    return result[0]

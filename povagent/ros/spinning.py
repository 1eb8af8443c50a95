"""An executor spun on a background thread that is stopped and joined before anything is destroyed.

rclpy's objects are C++ objects. A Python thread still inside one of their calls when the
interpreter exits is ended by ``pthread_exit``, whose forced unwinding through rclpy's
``noexcept`` frames aborts the process (``terminate called without an active exception``, exit
code 134) after the program's work is done. ``executor.spin`` on a daemon thread invites exactly
that: ``Executor.shutdown`` wakes the loop but does not wait for it, so the thread can still be in
its wait set while the nodes and the context are torn down.

:class:`BackgroundSpin` spins in short ``spin_once`` slices, so a stop request is seen within one
slice; leaving it stops the loop, joins the thread, then shuts the executor down (which joins a
multi-threaded executor's pool). Only after that may nodes be destroyed, then the context shut
down: executor, node, context, with no thread left spinning.

Nothing here imports rclpy at module level; the executor is whatever the caller built.
"""

from __future__ import annotations

import threading
from types import TracebackType
from typing import Any

#: Seconds one ``spin_once`` slice waits for work: how long a stop request may wait to be seen.
SLICE_S = 0.05


class SpinNotStopped(RuntimeError):
    """The spinning thread did not end within the timeout: destroying nodes now would be unsafe."""


class BackgroundSpin:
    """Spin ``executor`` on a thread while the ``with`` block runs; stop, join and shut it down on exit."""

    def __init__(self, executor: Any, *, name: str = "ros-executor", join_timeout_s: float = 10.0) -> None:
        self.executor = executor
        self._stop = threading.Event()
        self._join_timeout_s = join_timeout_s
        self._thread = threading.Thread(target=self._spin, name=name, daemon=True)
        self.error: BaseException | None = None
        self._slices = 0  # spin_once calls ended, for settle()
        self._sliced = threading.Condition()

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException, ShutdownException

        context = self.executor.context
        try:
            while not self._stop.is_set() and context.ok():
                self.executor.spin_once(timeout_sec=SLICE_S)
                with self._sliced:
                    self._slices += 1
                    self._sliced.notify_all()
        except (ExternalShutdownException, ShutdownException):
            return  # the context was shut down under us (Ctrl-C, SIGTERM): nothing left to spin
        except BaseException as exc:  # kept for stop() to re-raise on the caller's thread
            self.error = exc

    def start(self) -> BackgroundSpin:
        """Start spinning; returns ``self``."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the loop, join its thread, then shut the executor down (in that order)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(self._join_timeout_s)
            if self._thread.is_alive():
                raise SpinNotStopped(f"the executor thread did not stop within {self._join_timeout_s:g} s")
        self.executor.shutdown(timeout_sec=self._join_timeout_s)
        if self.error is not None:
            raise self.error

    def settle(self, timeout_s: float = 10.0) -> None:
        """Return once a ``spin_once`` slice that began after this call has ended (or the loop
        has ended): a node removed from the executor before the call is then in no wait set the
        loop builds, so it may be destroyed while the executor goes on spinning. Without this, the
        loop may be adding the node's entities to a wait set as they are destroyed
        (``InvalidHandle``), which ends the loop."""
        with self._sliced:
            target = self._slices + 2  # the slice running now may have taken the node; the next began after
            self._sliced.wait_for(lambda: self._slices >= target or not self._thread.is_alive(), timeout=timeout_s)

    @property
    def spinning(self) -> bool:
        """Whether the spinning thread is alive."""
        return self._thread.is_alive()

    def __enter__(self) -> BackgroundSpin:
        return self.start()

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.stop()


__all__ = ["SLICE_S", "BackgroundSpin", "SpinNotStopped"]

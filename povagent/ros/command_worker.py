"""The node's answering: a bounded queue of commands, one worker thread, one final result each.

The model is never called on the ROS executor: :meth:`CommandWorker.submit` (the ``~/command``
subscription) only queues a command, and one worker thread answers them in order. Every command
gets exactly one final result: its answer, ``queue_full`` when the queue is full (said at once,
never a silent drop), or ``internal_error`` when answering or publishing raised. The worker
outlives any exception: a bug in one answer is that command's ``internal_error`` result (its
traceback goes to the log), and the next command is answered. A command that has to wait is
told so first (``queued``, with its place).

This module knows nothing of ROS: it takes the function that answers and the one that
publishes, so the rules above are tested without a graph; :mod:`povagent.ros.node` wires them.
"""

from __future__ import annotations

import queue
import threading
import traceback
from typing import Callable

from povagent.ros.result import CommandResult, CommandStatus

#: Answers one command (blocking): :meth:`povagent.ros.session.GroundingSession.answer`.
Answer = Callable[[str], CommandResult]
#: Publishes one result (``~/result`` and, with a goal, the goal topics).
Publish = Callable[[CommandResult], None]
#: Logs a bug: a message and its traceback (the node's logger).
LogBug = Callable[[str], object]


class CommandWorker:
    """A bounded command queue served by one daemon thread (see the module docstring)."""

    def __init__(self, answer: Answer, publish: Publish, *, map_frame: str, max_queue: int, log_bug: LogBug | None = None) -> None:
        self._answer = answer
        self._publish = publish
        self._map_frame = map_frame
        self._log_bug = log_bug
        self._commands: queue.Queue[str | None] = queue.Queue(maxsize=max(1, max_queue))
        self._busy = threading.Event()
        self._submit_lock = threading.Lock()
        self._thread = threading.Thread(target=self._serve, name="povagent-ros-worker", daemon=True)
        self._thread.start()

    @property
    def max_queue(self) -> int:
        """How many commands may wait behind the one being answered."""
        return self._commands.maxsize

    @property
    def answering(self) -> bool:
        """Whether the worker is answering a command now."""
        return self._busy.is_set()

    def submit(self, command: str) -> None:
        """Queue ``command``; publish ``queued`` (it waits) or ``queue_full`` (it is refused, final)."""
        with self._submit_lock:  # one place in line per command, even from a multi-threaded executor
            waiting = self._commands.qsize() + (1 if self._busy.is_set() else 0)
            try:
                self._commands.put_nowait(command)
            except queue.Full:
                self._send(CommandResult(command=command, status=CommandStatus.QUEUE_FULL, map_frame=self._map_frame,
                                         reason=f"dropped: {waiting} command(s) ahead and the queue holds {self.max_queue}; send it again later"))
                return
        if waiting:
            self._send(CommandResult(command=command, status=CommandStatus.QUEUED, map_frame=self._map_frame,
                                     queue_position=waiting, reason=f"answered after {waiting} command(s) ahead"))

    def _serve(self) -> None:
        while True:
            command = self._commands.get()
            if command is None:
                return
            self._busy.set()
            try:
                result = self._answer(command)
            except Exception as exc:
                self._bug(f"answering {command[:80]!r} raised {type(exc).__name__}")
                result = self._internal_error(command, f"answering raised {type(exc).__name__}: {exc}")
            finally:
                self._busy.clear()
            self._send(result)

    def _send(self, result: CommandResult) -> None:
        """Publish ``result``; if that raises, publish its ``internal_error`` instead; never raise."""
        try:
            self._publish(result)
            return
        except Exception as exc:
            self._bug(f"publishing the result of {result.command[:80]!r} raised {type(exc).__name__}")
            fallback = self._internal_error(result.command, f"the {result.status} result could not be published: {type(exc).__name__}: {exc}")
        try:
            self._publish(fallback)
        except Exception:
            self._bug(f"publishing the internal_error result of {result.command[:80]!r} failed too")

    def _internal_error(self, command: str, reason: str) -> CommandResult:
        return CommandResult(command=command[:200], status=CommandStatus.INTERNAL_ERROR, map_frame=self._map_frame, reason=reason[:500])

    def _bug(self, message: str) -> None:
        if self._log_bug is not None:
            try:
                self._log_bug(f"{message}; a bug, please report it:\n{traceback.format_exc()}")
            except Exception:
                pass  # a logger that fails must not take the worker with it

    def close(self, timeout: float = 30.0) -> None:
        """Drop the commands still waiting and stop the worker after the one it is answering."""
        while True:
            try:
                self._commands.get_nowait()
            except queue.Empty:
                break
        self._commands.put(None)
        self._thread.join(timeout=timeout)


__all__ = ["Answer", "CommandWorker", "LogBug", "Publish"]

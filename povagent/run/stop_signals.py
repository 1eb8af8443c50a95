"""SIGTERM stops a run the way Ctrl-C does: cleanly, rows kept, the summary marked interrupted.

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
"""

from __future__ import annotations

import contextlib
import signal
import threading
from dataclasses import dataclass
from types import FrameType
from typing import Iterator

#: Exit codes of a run stopped by a signal (documented in the README's reliability section).
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT)
EXIT_TERMINATED = 143  # SIGTERM


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
        state.terminated = True
        handler = signal.getsignal(signal.SIGINT)
        if callable(handler):
            handler(signal.SIGINT, frame)  # asyncio.run's: cancel the main task; Python's: KeyboardInterrupt
        else:  # SIGINT ignored (a job started in the background): stop all the same
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        yield state
    finally:
        signal.signal(signal.SIGTERM, previous)

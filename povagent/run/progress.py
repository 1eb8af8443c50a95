"""Live progress of a run: done/total, rate, ETA and error counts, quiet when not on a terminal.

:func:`make_progress` returns a live rich bar on a TTY and a silent stand-in otherwise (CI logs
stay clean). Updates are cheap counters; rich redraws at its own pace. This module must not
know about rows or results beyond the counts it is given.
"""

from __future__ import annotations

import sys
from typing import Any, Protocol


class RunProgress(Protocol):
    """What the runner reports progress to."""

    def start(self, total: int, done: int) -> None:
        """The run begins: ``total`` keys, ``done`` already finished (resumed)."""

    def advance(self, status: str) -> None:
        """One key finished with this row status."""

    def concurrency(self, limit: int, maximum: int) -> None:
        """The requests allowed in flight changed: ``limit`` of ``maximum`` (adaptive
        concurrency lowers it after 429s and raises it again as requests succeed)."""

    def stop(self) -> None:
        """The run ended (also on interruption)."""


class QuietProgress:
    """Progress that shows nothing (not a terminal, or ``--quiet``); still counts."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self.limit: int | None = None

    def start(self, total: int, done: int) -> None:
        """Nothing to show."""

    def advance(self, status: str) -> None:
        """Count the status."""
        self.counts[status] = self.counts.get(status, 0) + 1

    def concurrency(self, limit: int, maximum: int) -> None:
        """Remember the current limit."""
        self.limit = limit

    def stop(self) -> None:
        """Nothing to close."""


#: Below this console width the bar drops its percentage and elapsed time, narrows, and
#: shortens its label, so that counts, rate and ETA stay on one 80-column line.
WIDE_CONSOLE = 110


class RichProgress:
    """A rich progress bar with error counts in the description."""

    def __init__(self, label: str = "run") -> None:
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            ProgressColumn,
            TaskProgressColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.table import Column

        from povagent.run.narrow_console import middle_ellipsis

        console = Console(file=sys.stderr)
        wide = console.width >= WIDE_CONSOLE
        self.label = middle_ellipsis(label, 40 if wide else 20)
        self.counts: dict[str, int] = {}
        columns: list[ProgressColumn] = [
            TextColumn("[bold]{task.description}"),
            BarColumn(bar_width=40 if wide else 12),
            MofNCompleteColumn(),
            *([TaskProgressColumn()] if wide else []),
            TextColumn("{task.fields[rate]}"),
            *([TimeElapsedColumn()] if wide else []),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            # error counts and the rate-limit note wrap under each other rather than being cut
            TextColumn("{task.fields[errors]} {task.fields[limit]}", table_column=Column(no_wrap=False, overflow="fold")),
        ]
        self._progress = Progress(*columns, console=console, refresh_per_second=4, transient=False)
        self._task: Any = None
        self._started_at = 0.0
        self._finished_now = 0

    def start(self, total: int, done: int) -> None:
        """Show the bar, already advanced by the resumed keys."""
        import time

        self._started_at = time.monotonic()
        self._task = self._progress.add_task(self.label, total=total, completed=done, rate="", errors="", limit="")
        self._progress.start()

    def advance(self, status: str) -> None:
        """Advance by one and refresh the rate and error counts."""
        import time

        self.counts[status] = self.counts.get(status, 0) + 1
        self._finished_now += 1
        elapsed = max(time.monotonic() - self._started_at, 1e-9)
        errors = " ".join(f"[red]{k}={v}" for k, v in sorted(self.counts.items()) if k != "answered")
        self._progress.update(self._task, advance=1, rate=f"{self._finished_now / elapsed:.1f}/s", errors=errors)

    def concurrency(self, limit: int, maximum: int) -> None:
        """Show the in-flight limit while rate limits hold it below ``concurrency``."""
        if self._task is not None:
            shown = "" if limit >= maximum else f"[yellow]in flight <= {limit}/{maximum} (429s)"
            self._progress.update(self._task, limit=shown)

    def stop(self) -> None:
        """Stop redrawing (the last state stays on screen)."""
        self._progress.stop()


def make_progress(label: str = "run", *, quiet: bool = False) -> RunProgress:
    """A live bar on a terminal; a silent counter when ``quiet`` or stderr is not a TTY."""
    if quiet or not sys.stderr.isatty():
        return QuietProgress()
    return RichProgress(label)

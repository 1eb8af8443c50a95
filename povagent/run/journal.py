"""The row journal: ``results.jsonl`` written durably, in batches, off the event loop.

Finished rows are queued and written together with one fsync in a worker thread (group
commit); only then are they reported, so no row is ever reported done before it is durable and
a run killed at any moment loses nothing it reported. :func:`drop_rows` rewrites a results file
without some keys (atomically), for re-attempting keys that failed.
"""

from __future__ import annotations

import asyncio
import json
import time
from pathlib import Path
from typing import Callable

from povagent.files.confined_read import open_regular
from povagent.files.confined_write import ConfinedFolder
from povagent.results.output_check import checking
from povagent.results.rows import ResultRow, ResultsWriter, row_line


class RowJournal(ResultsWriter):
    """``results.jsonl`` with group commit.

    :meth:`submit` queues a finished row and returns at once, so a worker moves on to its next
    key while the row is being made durable. Queued rows are written and fsynced together,
    in a worker thread (the event loop keeps serving requests meanwhile); only then is
    ``on_durable(row)`` called for each, which is where progress and observers hear of it.
    ``before_write()``, when given, runs in that thread before each batch is written (the
    runner pushes its log to the OS and stores queued answers in the response cache there); if
    it raises, the batch is not written and the run stops as for a failed write.
    """

    def __init__(
        self, path: str | Path, on_durable: Callable[[ResultRow], None], before_write: Callable[[], None] | None = None
    ) -> None:
        super().__init__(path)
        self._on_durable = on_durable
        self._before_write = before_write
        self._queue: list[tuple[str, ResultRow]] = []
        self._committer: asyncio.Task[None] | None = None
        self.error: BaseException | None = None
        self.fsyncs = 0
        self.fsync_s = 0.0
        #: whether rows are checked against the shipped schema (tests), asked once a run
        self._checked = checking()

    def submit(self, row: ResultRow) -> None:
        """Queue a finished row for the next batch (raises if an earlier batch failed)."""
        if self.error is not None:
            raise self.error
        self._queue.append((row_line(row, self.path, checked=self._checked), row))
        if self._committer is None or self._committer.done():
            self._committer = asyncio.get_running_loop().create_task(self._commit_loop())

    async def _commit_loop(self) -> None:
        while self._queue and self.error is None:
            # Yield once so rows finishing in this same tick join the batch.
            await asyncio.sleep(0)
            batch, self._queue = self._queue, []
            try:
                await asyncio.to_thread(self._write, "".join(line for line, _ in batch))
            except Exception as exc:  # a full disk ends the run; the rows are not reported
                # Kept here and raised to the workers by submit()/drain(); the task itself ends
                # quietly (re-raising would leave an exception nobody retrieves).
                self.error = exc
                return
            except BaseException as exc:  # cancelled mid-write: the batch's fate is unknown
                self.error = exc
                raise
            for _, row in batch:
                self._on_durable(row)

    async def backpressure(self, max_queued: int = 256) -> None:
        """Yield to the event loop; wait for the committer while too many rows are queued."""
        await asyncio.sleep(0)
        while len(self._queue) >= max_queued and self._committer is not None and not self._committer.done():
            await asyncio.shield(self._committer)

    async def drain(self) -> None:
        """Wait until every submitted row is durable; re-raise a write failure."""
        while self._committer is not None and not self._committer.done():
            await asyncio.shield(self._committer)
        if self.error is not None:
            raise self.error

    async def aclose(self) -> None:
        """Make what was submitted durable (also after a cancellation), then close the file."""
        try:
            await self.drain()
        except BaseException:  # already reported by the run; closing must still happen
            pass
        try:
            self.close()
        except OSError:  # the tail of a batch that failed (a full disk): already in ``error``
            if self.error is None:
                raise

    def _write(self, text: str) -> None:
        if self._before_write is not None:
            self._before_write()
        t0 = time.perf_counter()
        self.write_lines(text)
        self.fsyncs += 1
        self.fsync_s += time.perf_counter() - t0


def drop_rows(results: Path, keys: set[str]) -> None:
    """Rewrite ``results`` without the rows of ``keys``, atomically (a kill leaves the old file
    or the new one, never half of each); every other complete line is kept byte for byte.

    Each line is parsed to read its key: a key is never guessed from the line's text. A torn
    last line (no newline: a kill or a full disk mid-write, cut at any byte) is dropped, as the
    writer would cut it anyway.
    """
    # Bytes, not text: a torn tail may end inside a character, and every kept line is copied as is.
    # Staged beside and renamed over ``results``: a link planted at either name is never followed.
    with open_regular(results, what="results file") as src, ConfinedFolder(results.parent) as folder, folder.staged(results.name, encoding=None) as staged:
        dst = staged.file
        for line in src:
            if not line.endswith(b"\n"):
                continue
            try:
                record = json.loads(line)
            except (ValueError, RecursionError):  # not UTF-8, not JSON: not a row of ``keys``
                record = None
            key = record.get("key") if isinstance(record, dict) else None
            if key not in keys:
                dst.write(line)
        staged.commit(fsync=True)

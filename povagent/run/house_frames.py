"""The frames of a run's houses in the image store: read ahead off the event loop, held while
a house has keys left, let go after its last one.

:class:`FrameReader` reads an instance's new frames into the store in a worker thread, once
however many keys need them at once; :class:`HouseFrames` holds each house's frame files while
any of its pending keys is left. Both serve :mod:`povagent.run.runner`'s fan-out.
"""

from __future__ import annotations

import asyncio
import functools
from pathlib import Path
from typing import Any

from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore


def _forget_reads(reads: dict[Any, Any], paths: list[Any], _task: object) -> None:
    """Done callback of a frame-reading task: its files are no longer being read."""
    for p in paths:
        reads.pop(p, None)


def _read_files(images: ImageStore, paths: list[Path]) -> None:
    """Add image files to the store (in a worker thread); unreadable ones are skipped here."""
    for path in paths:
        try:
            images.load_file(path)
        except Exception:  # the strategy meets the same error and the row records it
            pass


class FrameReader:
    """Reads instances' frames into one image store (see :meth:`read`)."""

    def __init__(self, images: ImageStore) -> None:
        self.images = images
        self._reads: dict[Path, asyncio.Future[Any]] = {}
        self._frames_read: dict[int, tuple[Any, ...]] = {}
        self._frames_waits: dict[int, tuple[tuple[Any, ...], set[asyncio.Future[Any]]]] = {}

    async def read(self, instance: Instance) -> None:
        """Read the instance's new frames into the image store in a worker thread, once each.

        Strategies read images synchronously; a new house's 30 frames read on the event loop
        would stall every request in flight. Here the frames not yet in the store are read in
        one thread call (however many workers need them at once), and the strategy then finds
        them in the store. A file that cannot be read is left for the strategy to meet (and
        report) itself.
        """
        frames = instance.frames
        frames_id = id(frames)
        if self._frames_read.get(frames_id) is frames:
            return  # A/B instances of a house share one frames tuple: checked once, not per key
        images = self.images
        # The other keys of a house arrive while its frames are being read: they wait for the
        # reads the first one found, without looking at every frame again.
        known = self._frames_waits.get(frames_id)
        if known is not None and known[0] is frames and not all(w.done() for w in known[1]):
            waits = known[1]
        else:
            reads = self._reads
            new = [f.file for f in frames if f.file not in reads and not images.has_bytes(f.file)]
            if new:
                task = asyncio.ensure_future(asyncio.to_thread(_read_files, images, new))
                for path in new:
                    reads[path] = task
                task.add_done_callback(functools.partial(_forget_reads, reads, new))
            waits = {reads[f.file] for f in frames if f.file in reads}
            if waits:
                # Holding the tuple keeps its id from being reused while the entry lives.
                self._frames_waits[frames_id] = (frames, waits)
        if waits:
            await asyncio.gather(*waits)
            if self._frames_read.get(frames_id) is frames:
                return  # another key of the house checked them meanwhile
        if all(images.knows_file(f.file) for f in frames):
            self._frames_read[frames_id] = frames
            self._frames_waits.pop(frames_id, None)


class HouseFrames:
    """Holds each house's frame files in the image store while any of its pending keys is left,
    and lets them go after the last one (keys come house by house: the store then keeps the
    houses in flight, whatever the run's length)."""

    def __init__(self, images: ImageStore, pending: list[tuple[Instance, int]]) -> None:
        self._images = images
        self._left: dict[str, int] = {}
        self._files: dict[str, set[Path]] = {}
        # a house's frames once per frames tuple (a set's 10,000 items share a few dozen: see
        # ImageLookups.shared), not once per key; ``pending`` holds the tuples, so an id is one
        seen: set[tuple[str, int]] = set()
        for instance, _ in pending:
            house, frames = instance.house_id, instance.frames
            self._left[house] = self._left.get(house, 0) + 1
            if (house, id(frames)) not in seen:
                seen.add((house, id(frames)))
                self._files.setdefault(house, set()).update(f.file for f in frames)
        for files in self._files.values():
            images.hold_files(files)

    def done(self, instance: Instance) -> None:
        """One key of ``instance``'s house has its row."""
        house = instance.house_id
        left = self._left.get(house, 0) - 1
        self._left[house] = left
        if left == 0:
            self._images.release_files(self._files.pop(house))

    def __enter__(self) -> HouseFrames:
        return self

    def __exit__(self, *exc: object) -> None:
        """Let go of the houses still held (a run that stopped early)."""
        for files in self._files.values():
            self._images.release_files(files)
        self._files.clear()

"""The agent's memory of the frames it was handed bare: the same content, the same shown frame.

What it is for: a robot app often hands ``locate`` the very same frames again (the last few
camera images, as numpy arrays or files) without wrapping them in a
:class:`~povagent.agent.shown_frame.ShownFrame`. Each frame is known by a digest of its content
(:func:`~povagent.agent.shown_frame.content_digest`: an array's shape, type and bytes, a PIL
image's pixels, a file's bytes), which costs a hash where a letterbox and a PNG encode cost
a resize and a compression; a frame seen before gets back the shown frame made for it then, with
its name, letterbox and encoding. An array is copied when first remembered, so a buffer the app
reuses for its next image never changes a remembered frame; a file is known by its path and its
bytes, so an edited file is a new frame.

What it must not do: hold without bound. It keeps the most recently used frames up to
:data:`MAX_REMEMBERED_BYTES` (counted as the source's pixels plus a square and its PNG).
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict

import numpy as np

from povagent.agent.frame_inputs import FrameInput
from povagent.agent.shown_frame import ShownFrame, content_digest
from povagent.errors import ReadTargetError
from povagent.geometry.letterbox import BENCHMARK_SIZE

#: The most bytes the frames remembered may hold: about a hundred 640x480 frames.
MAX_REMEMBERED_BYTES = 256 << 20
#: A square's RGB pixels and (at most about as much again) its PNG encoding.
_SQUARE_BYTES = 2 * 3 * BENCHMARK_SIZE * BENCHMARK_SIZE


class FrameMemory:
    """Shown frames by the content they were made from, most recently used kept (thread-safe)."""

    def __init__(self, max_bytes: int = MAX_REMEMBERED_BYTES) -> None:
        self.max_bytes = max_bytes
        self._lock = threading.Lock()
        self._frames: OrderedDict[tuple[object, ...], tuple[ShownFrame, int]] = OrderedDict()
        self._held = 0

    def __len__(self) -> int:
        return len(self._frames)

    def shown(self, frame: FrameInput, what: str, pad_color: tuple[int, int, int]) -> ShownFrame:
        """The prepared shown frame of ``frame`` (the one made before, for the same content and
        padding); a frame that cannot be used is a :class:`~povagent.errors.BadInputError`
        naming ``what``."""
        try:
            content = content_digest(frame)
        except (OSError, ReadTargetError):
            # not readable as a file: the shown frame says why, naming the frame
            shown = ShownFrame(frame, pad_color)
            shown.prepare(what)
            return shown
        source: object = os.fspath(frame) if isinstance(frame, (str, os.PathLike)) else type(frame).__name__
        key = (source, content, tuple(pad_color))
        with self._lock:
            hit = self._frames.get(key)
            if hit is not None:
                self._frames.move_to_end(key)
                return hit[0]
        # a copy: the app may write its next image into the same buffer
        own = np.array(frame, copy=True) if isinstance(frame, np.ndarray) else frame
        shown = ShownFrame(own, pad_color)
        shown.prepare(what, content)
        width, height = shown.box.original
        # the source's pixels (an array as given, else decoded RGB) and a square with its PNG
        held = (frame.nbytes if isinstance(frame, np.ndarray) else 3 * width * height) + _SQUARE_BYTES
        self._remember(key, shown, held)
        return shown

    def _remember(self, key: tuple[object, ...], shown: ShownFrame, size: int) -> None:
        with self._lock:
            if key in self._frames:
                return  # another thread made it meanwhile: either is the same frame
            self._frames[key] = (shown, size)
            self._held += size
            while self._held > self.max_bytes and len(self._frames) > 1:
                _, (_, dropped) = self._frames.popitem(last=False)
                self._held -= dropped


__all__ = ["MAX_REMEMBERED_BYTES", "FrameMemory"]

"""Buffers kept per thread for frames of one size, made again when the size changes.

What it is for: the renderer and the frame encoder fill frame-sized scratch arrays for every
frame; a fresh frame-sized array costs its page faults every time, so each thread keeps the last
ones it made (threads render and encode at once: a buffer is never shared). What it must not
do: hand a buffer made for another size, or one thread's buffer to another thread.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import TypeVar

T = TypeVar("T")


def kept_for(local: threading.local, name: str, size: Hashable, make: Callable[[], T]) -> T:
    """This thread's object kept under ``name`` in ``local``, made by ``make`` when this thread
    has none yet or made it for another ``size``."""
    kept: tuple[Hashable, T] | None = getattr(local, name, None)
    if kept is None or kept[0] != size:
        kept = (size, make())
        setattr(local, name, kept)
    return kept[1]

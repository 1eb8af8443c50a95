"""What exists when a run fans out (the loaded set, its plan, the imported code), kept out of the
collector's full passes while the keys run.

CPython's cyclic collector walks every tracked object at each full collection, and a run makes
several of them as it allocates rows: with a 10,000-item set loaded, those walks cost a choice
run about 20 microseconds of CPU a key, work that grows with the set, not with the key.
:func:`frozen_heap` moves every object that exists when it is entered into the permanent
generation (:func:`gc.freeze`) and back when it is left (:func:`gc.unfreeze`), so full passes
meanwhile walk only what the run made since. Nothing is freed later than it would be, except
cyclic garbage that already existed at the freeze: it is collected after the keys instead of
during them.

A process that froze objects itself (a server that forks its workers) keeps its own freeze:
the run then freezes nothing. Runs inside one another, or side by side in one process (a
sweep's cells), freeze in turn and thaw once, when the last of them is done.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

_lock = threading.Lock()
#: how many runs are inside :func:`frozen_heap` now
_inside = 0


@contextlib.contextmanager
def frozen_heap() -> Iterator[None]:
    """Every object existing now left out of full collections until the block ends (see the
    module's docstring); nothing is done when someone else's freeze is in place."""
    global _inside
    with _lock:
        if _inside == 0 and gc.get_freeze_count() > 0:
            ours = False  # not ours to thaw
        else:
            ours = True
            _inside += 1
            gc.freeze()
    try:
        yield
    finally:
        if ours:
            with _lock:
                _inside -= 1
                if _inside == 0:
                    gc.unfreeze()

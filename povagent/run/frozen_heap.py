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

:func:`spaced_collections` spaces the collector's young passes out while a run opens its set and
runs its keys: CPython starts one every 700 container objects allocated on balance, and each
walks every young object still alive (the rows waiting for their batch, the records of the set
being read) and later the middle generation again; a run makes almost no cyclic garbage, so
those passes found nothing and cost a choice run about 8 microseconds a key, and a 10,000-item
set's reading one full pass over the whole heap (40 ms). With the young threshold at
:data:`YOUNG_THRESHOLD` the same garbage is still collected, by passes a thirtieth as frequent;
what it can hold meanwhile is at most that many objects. The threshold is put back when the
last run inside is done, unless someone else changed it meanwhile.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

_lock = threading.Lock()
#: how many runs are inside :func:`frozen_heap` now
_inside = 0
#: the young generation's threshold inside :func:`spaced_collections` (CPython's default: 700)
YOUNG_THRESHOLD = 20_000
#: how many runs are inside :func:`spaced_collections` now, and the thresholds it replaced
_spaced = 0
_replaced: tuple[int, ...] | None = None


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


@contextlib.contextmanager
def spaced_collections() -> Iterator[None]:
    """The collector's young passes at most every :data:`YOUNG_THRESHOLD` allocations until the
    block ends (see the module's docstring); a higher threshold already set is kept."""
    global _spaced, _replaced
    with _lock:
        if _spaced == 0:
            before = gc.get_threshold()
            _replaced = None
            if before[0] < YOUNG_THRESHOLD and before[0] != 0:  # 0: collection is off, left so
                _replaced = before
                gc.set_threshold(YOUNG_THRESHOLD, *before[1:])
        _spaced += 1
    try:
        yield
    finally:
        with _lock:
            _spaced -= 1
            if _spaced == 0 and _replaced is not None:
                if gc.get_threshold() == (YOUNG_THRESHOLD, *_replaced[1:]):  # nobody changed it meanwhile
                    gc.set_threshold(*_replaced)
                _replaced = None

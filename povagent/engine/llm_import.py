"""The one way povagent imports litellm: lazily, offline-safe, quiet, and early when it pays.

``import litellm`` costs seconds and, unless told otherwise, fetches a model cost map from the
network and loads stray ``.env`` files. Everything that needs litellm calls
:func:`import_litellm` at the moment it needs it, so ``povagent --help``, offline baselines and
replays never import it. This module must stay tiny and must not import litellm at import time.

A run that will surely send a request calls :func:`preload_litellm` first: litellm is then
imported (and warmed up) in a background thread while the run loads its dataset and builds
its first requests. Python's import locks are per module: a thread importing a module another
thread is importing waits for it, and a cycle between two threads' imports (each holding a
module the other needs) is broken by handing one of them a half-initialised module. So while
the background import runs, nothing else may import litellm or what it imports (openai): every
caller goes through :func:`import_litellm`, which waits for the background thread before it
touches the import system, and imports litellm itself when the background import failed.

The import and warm-up run with Python's cyclic garbage collector paused: they create about
a million objects (litellm's and openai's classes, pydantic schemas, the cost map), none of
them garbage, and each threshold crossed on the way set off a collection that walked all of
them again, a quarter of the import's CPU. In povagent's own processes (the console script
calls :func:`freeze_after_loading`) what is loaded is then moved out of the collector's sight
(``gc.freeze``): module-level objects that live as long as the process, which the next full
collection would otherwise walk once more (~0.5 s). A program that embeds povagent (a robot
app's :class:`~povagent.agent.GroundingAgent`) gets the pause only: a freeze would also take
in the app's own objects of that moment, and a cycle among them that became garbage later
would never be collected. Objects freed by reference counting are freed as usual either way.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import os
import threading
from collections.abc import Iterator
from types import ModuleType

#: litellm, once imported and set up.
_litellm: ModuleType | None = None
#: Held while litellm is being imported and set up (by whichever thread does it).
_import_lock = threading.Lock()
#: Freeze what the import loaded (see the module's docstring): povagent's own processes only.
_freeze_loaded = False
#: The background import started by :func:`preload_litellm`, if any.
_preload: threading.Thread | None = None
_preload_lock = threading.Lock()


def import_litellm() -> ModuleType:
    """Import and return litellm, set up for closed networks and clean logs.

    Before the first import: ``LITELLM_LOCAL_MODEL_COST_MAP=True`` (use the cost map bundled
    with the package instead of downloading one) and ``LITELLM_MODE=PRODUCTION`` (do not load
    ``.env`` files). Both are defaults: a value the user exported wins.

    ``MAX_BASE64_LENGTH_FOR_LOGGING`` (also read at import) is left alone: litellm's truncation
    of base64 for logging is skipped per call instead, for povagent's calls only and only while
    nothing can read litellm's logging payload (:mod:`povagent.engine.llm_logging`).

    Safe from any thread: while :func:`preload_litellm`'s thread imports, callers wait for it.
    """
    global _litellm
    if _litellm is not None:
        return _litellm
    wait_for_preload()
    with _import_lock:
        if _litellm is None:
            os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
            os.environ.setdefault("LITELLM_MODE", "PRODUCTION")
            with collector_paused(freeze=_freeze_loaded):
                import litellm

            # the "Give Feedback / Get Help" banner on every exception drowns our own error messages
            litellm.suppress_debug_info = True
            # anonymous usage telemetry would be a network call we never asked for
            litellm.telemetry = False
            _litellm = litellm
    return _litellm


def preload_litellm(model: str) -> None:
    """Start importing litellm and warming it up for ``model`` in a daemon thread; return at once.

    Call it only when a request will surely be sent (an import that is not needed costs
    seconds of CPU). Once per process; a failure in the thread is not reported here: the
    caller's own :func:`import_litellm` then imports again and raises it.
    """
    global _preload
    with _preload_lock:
        if _preload is not None or _litellm is not None:
            return
        _preload = threading.Thread(target=_preload_quietly, args=(model,), name="povagent-preload-litellm", daemon=True)
        _preload.start()


def wait_for_preload() -> None:
    """Wait until the background import of :func:`preload_litellm` (if any) has ended."""
    thread = _preload
    if thread is not None and thread is not threading.current_thread():
        thread.join()


def _preload_quietly(model: str) -> None:
    try:
        _warm_up(model)
    except Exception:  # the foreground import meets the same failure and reports it
        pass


@functools.cache
def warm_up_litellm(model: str) -> None:
    """Load what litellm loads lazily on its first request (about 460 modules of the OpenAI
    client and litellm's own: seconds on a busy machine), so that cost never counts against
    the first request's timeout. Makes no network call: the OpenAI client is only built and
    the completion is litellm's ``mock_response``. Runs once per model string and process
    (after a preload of the same model, at once).
    """
    wait_for_preload()
    _warm_up(model)


@functools.cache
def _warm_up(model: str) -> None:
    litellm = import_litellm()
    with collector_paused(freeze=_freeze_loaded):
        import openai

        client = openai.AsyncOpenAI(api_key="warm-up", base_url="http://127.0.0.1:9/v1")
        _ = client.chat.completions  # the resources module tree loads on first access
        try:
            litellm.completion(model=model, messages=[{"role": "user", "content": "warm-up"}], mock_response="ok")
        except Exception:  # a warm-up only saves time: a model string litellm cannot route fails later, for real
            pass


def freeze_after_loading() -> None:
    """Freeze what litellm's import loads (see the module's docstring): for a process that is
    povagent's own, such as the console script, never for a program that embeds povagent."""
    global _freeze_loaded
    _freeze_loaded = True


@contextlib.contextmanager
def collector_paused(freeze: bool = False) -> Iterator[None]:
    """Pause the cyclic garbage collector for a bulk load of long-lived objects and, with
    ``freeze``, move every object tracked at the end out of its sight (``gc.freeze``). The
    collector's earlier state comes back: a caller that had turned it off keeps it off.
    Process-wide, so only for loads of seconds."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if freeze:
            gc.freeze()
        if was_enabled:
            gc.enable()

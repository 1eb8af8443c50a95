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

An import is untrusted in one way: it may never end (a broken install, a network file system)
or fail late. Async callers wait through :func:`import_litellm_async`, which runs the import in
a daemon thread of its own and waits at most :func:`import_deadline_s`: the event loop stays
free, so SIGINT/SIGTERM end a run at any point of its start-up, and neither the loop's
shutdown nor the interpreter's exit waits for a thread stuck in an import. The first failure
(an error or the deadline) is remembered and raised to every later caller as
:class:`LiteLLMUnavailable`, one line: an import that failed after 20 s is never waited for twice.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import gc
import os
import threading
from collections.abc import Callable, Iterator
from types import ModuleType
from typing import TypeVar

from povagent.engine.daemon_threads import in_daemon_thread as daemon_thread_future

_T = TypeVar("_T")

#: How long an import of litellm may take before it counts as failed (seconds). A healthy
#: import takes seconds even on a loaded machine; ``POVAGENT_LITELLM_IMPORT_TIMEOUT`` overrides.
DEFAULT_IMPORT_DEADLINE_S = 120.0


class LiteLLMUnavailable(RuntimeError):
    """litellm could not be imported (missing, broken, or still importing at the deadline).

    Its message is one line that says what happened and what to do."""

#: litellm, once imported and set up.
_litellm: ModuleType | None = None
#: Held while litellm is being imported and set up (by whichever thread does it).
_import_lock = threading.Lock()
#: Freeze what the import loaded (see the module's docstring): povagent's own processes only.
_freeze_loaded = False
#: The background import started by :func:`preload_litellm`, if any.
_preload: threading.Thread | None = None
_preload_lock = threading.Lock()
#: The first failed import's one-line reason; every later caller gets it at once.
_failure: str | None = None


def import_deadline_s() -> float:
    """Seconds an import may take: ``POVAGENT_LITELLM_IMPORT_TIMEOUT`` (positive) or the default."""
    raw = os.environ.get("POVAGENT_LITELLM_IMPORT_TIMEOUT", "")
    try:
        value = float(raw)
    except ValueError:
        return DEFAULT_IMPORT_DEADLINE_S
    return value if 0 < value < float("inf") else DEFAULT_IMPORT_DEADLINE_S


def _remember_failure(exc: BaseException) -> str:
    global _failure
    if _failure is None:
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        hint = (
            "check the Python environment (an import that never ends: a hung file system or a broken package)"
            if isinstance(exc, TimeoutError)
            else "reinstall povagent's dependencies (pip install povagent)"
        )
        _failure = f"cannot import litellm ({type(exc).__name__}{': ' + detail if detail else ''}): {hint}"
    return _failure


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
    if _failure is not None:
        raise LiteLLMUnavailable(_failure)
    with _import_lock:
        if _failure is not None:
            raise LiteLLMUnavailable(_failure)
        if _litellm is None:
            os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
            os.environ.setdefault("LITELLM_MODE", "PRODUCTION")
            try:
                with collector_paused(freeze=_freeze_loaded):
                    import litellm
            except Exception as exc:  # ImportError, or whatever a broken install raises while importing
                raise LiteLLMUnavailable(_remember_failure(exc)) from None

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
    """Wait until the background import of :func:`preload_litellm` (if any) has ended, at most
    :func:`import_deadline_s` seconds; a preload still importing then counts as failed."""
    thread = _preload
    if thread is not None and thread is not threading.current_thread():
        thread.join(import_deadline_s())
        if thread.is_alive():
            raise LiteLLMUnavailable(_remember_failure(TimeoutError(f"still importing after {import_deadline_s():g} s")))


def _preload_quietly(model: str) -> None:
    try:
        _warm_up(model)
    except Exception:  # remembered by import_litellm: the foreground caller reports it, once
        pass


async def import_litellm_async() -> ModuleType:
    """:func:`import_litellm` for async callers: in a daemon thread, at most
    :func:`import_deadline_s` seconds, cancellable at any moment (see the module's docstring)."""
    if _litellm is not None:
        return _litellm
    if _failure is not None:
        raise LiteLLMUnavailable(_failure)
    return await in_daemon_thread(import_litellm, "povagent-import-litellm")


async def warm_up_litellm_async(model: str) -> None:
    """:func:`warm_up_litellm` for async callers, bounded and cancellable like the import."""
    await in_daemon_thread(lambda: warm_up_litellm(model), "povagent-warm-up-litellm")


async def in_daemon_thread(fn: Callable[[], _T], name: str) -> _T:
    """Run ``fn`` in a new daemon thread and wait for it at most :func:`import_deadline_s`.

    Not the loop's default executor (see :mod:`povagent.engine.daemon_threads`): one stuck in an
    import would hold a cancelled run forever."""
    deadline = import_deadline_s()
    try:
        return await asyncio.wait_for(daemon_thread_future(fn, name), deadline)
    except TimeoutError:
        reason = _remember_failure(TimeoutError(f"still importing after {deadline:g} s"))
        raise LiteLLMUnavailable(reason) from None


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

"""One headless Chromium for the whole test session, driven from a thread of its own.

Playwright's sync API runs its event loop in the thread that starts it and leaves that loop
marked as running there: ``asyncio.run`` (the runner's, the tests' own) then refuses to start in
that thread. A browser kept for the session in the main thread would break every later test
that runs a pipeline, so Playwright and Chromium live in one worker thread
(:class:`BrowserThread`), and tests reach them through :class:`OnBrowserThread`, which makes
each call there and hands back the result. Launching Chromium costs about a second of CPU:
once a session instead of once a module or once a page load.
"""

from __future__ import annotations

import concurrent.futures
import queue
import threading
from collections.abc import Callable
from typing import Any


class BrowserThread:
    """Playwright and one launched Chromium, owned by a worker thread; :meth:`call` runs a
    function there. ``launch(playwright) -> browser`` is called in the thread once."""

    def __init__(self, launch: Callable[[Any], Any]) -> None:
        self._jobs: queue.Queue = queue.Queue()
        ready: concurrent.futures.Future = concurrent.futures.Future()
        self._thread = threading.Thread(target=self._serve, args=(launch, ready), name="session-chromium", daemon=True)
        self._thread.start()
        self.browser = ready.result()  # a launch error is raised here, in the test that asked

    def _serve(self, launch: Callable[[Any], Any], ready: concurrent.futures.Future) -> None:
        from playwright.sync_api import sync_playwright

        try:
            with sync_playwright() as p:
                browser = launch(p)
                ready.set_result(browser)
                try:
                    while (job := self._jobs.get()) is not None:
                        fn, args, kwargs, done = job
                        try:
                            done.set_result(fn(*args, **kwargs))
                        except BaseException as err:  # handed to the caller, the thread serves on
                            done.set_exception(err)
                finally:
                    browser.close()
        except BaseException as err:
            if not ready.done():
                ready.set_exception(err)
            else:
                raise

    def call(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """``fn(*args, **kwargs)`` run in the browser's thread; its result, or its exception."""
        if threading.current_thread() is self._thread:
            return fn(*args, **kwargs)  # a callback Playwright runs (page.on): already there
        done: concurrent.futures.Future = concurrent.futures.Future()
        self._jobs.put((fn, args, kwargs, done))
        return done.result()

    def close(self, timeout: float = 60.0) -> None:
        """Close Chromium and stop Playwright's driver."""
        self._jobs.put(None)
        self._thread.join(timeout)


def _playwright_object(value: Any) -> bool:
    return type(value).__module__.startswith("playwright.")


class OnBrowserThread:
    """A Playwright object used from any thread: every attribute read and method call runs in
    the browser's thread, and Playwright objects come back wrapped the same way (``page =
    browser.new_page(...)``, ``page.keyboard.press("3")``, ``page.locator(...).count()``)."""

    __slots__ = ("_obj", "_runner")

    def __init__(self, obj: Any, runner: BrowserThread) -> None:
        object.__setattr__(self, "_obj", obj)
        object.__setattr__(self, "_runner", runner)

    def _wrap(self, value: Any) -> Any:
        if _playwright_object(value):
            return OnBrowserThread(value, self._runner)
        if isinstance(value, list):
            return [self._wrap(v) for v in value]
        return value

    def __getattr__(self, name: str) -> Any:
        obj, runner = self._obj, self._runner
        if callable(getattr(type(obj), name, None)):  # a method: called there, in one hop

            def method(*args: Any, **kwargs: Any) -> Any:
                args = tuple(_unwrap(a) for a in args)
                kwargs = {k: _unwrap(v) for k, v in kwargs.items()}
                return self._wrap(runner.call(lambda: getattr(obj, name)(*args, **kwargs)))

            return method
        return self._wrap(runner.call(getattr, obj, name))  # a property (page.url, page.keyboard)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{name}: Playwright objects are not assigned to from the tests")

    def __repr__(self) -> str:
        return f"OnBrowserThread({self._obj!r})"


def _unwrap(value: Any) -> Any:
    return value._obj if isinstance(value, OnBrowserThread) else value


#: The page :func:`kept_page` hands out (``"page"``) and its context (``"context"``, unwrapped).
_kept: dict[str, Any] = {}


def kept_page(browser: OnBrowserThread, viewport: tuple[int, int]) -> OnBrowserThread:
    """The session's kept page, on ``about:blank`` with its window ``viewport`` (width,
    height), ready for a load that shares nothing with the one before.

    One page is kept for the session's loads of a report or a gallery, across tests and
    modules (tests/conftest.py's ``browser`` leaves it open): opening a page costs Chromium
    about half a second of CPU (a renderer process and a context of their own), a load into a
    kept page a tenth of that. ``about:blank`` first makes the next load a new document even
    when its URL differs from the last only after ``#`` (no same-document jump). What such a
    page shares with the one before is its origin's storage (every load into it is checked to
    leave none: :data:`KEPT_IN_STORAGE`) and the renderer process; files are read again at
    each load (one rewritten between two loads of a URL shows its new content)."""
    page = _kept.get("page")
    if page is None or page.is_closed():
        page = _kept["page"] = browser.new_page()
        _kept["context"] = _unwrap(page.context)
    page.set_viewport_size({"width": viewport[0], "height": viewport[1]})
    page.goto("about:blank")
    return page


def is_kept(context: Any) -> bool:
    """Whether the (unwrapped) browser context is the kept page's (:func:`kept_page`)."""
    return context is _kept.get("context")


#: How many items the loaded page keeps in its origin's storage (0 where storage is refused):
#: checked after a load into a :func:`kept_page`, so no load can see what an earlier one kept.
KEPT_IN_STORAGE = "() => { try { return localStorage.length + sessionStorage.length; } catch (e) { return 0; } }"

"""A client that hangs up is not a server error: quiet tracebacks for expected disconnects.

``socketserver`` prints "Exception occurred during processing of request from ..." and a
traceback to stderr for any exception a handler raises. A client that gave up (its timeout
passed, it was cancelled) makes the handler's next write fail with a broken pipe or a reset
connection: expected, and nothing to fix. :class:`QuietDisconnects` drops exactly those and
leaves every other exception printed as before. Used by the static image server and the test
servers (:mod:`povagent.testing`).
"""

from __future__ import annotations

import sys
from typing import Any

#: What a handler sees when its client went away mid-request.
CLIENT_DISCONNECTS: tuple[type[BaseException], ...] = (BrokenPipeError, ConnectionResetError, ConnectionAbortedError, TimeoutError)


class QuietDisconnects:
    """Mixin for a ``socketserver`` server class, listed before it:
    ``class _Server(QuietDisconnects, ThreadingHTTPServer)``."""

    def handle_error(self, request: Any, client_address: Any) -> None:
        """Stay quiet when the client disconnected; print any other error as socketserver does."""
        if isinstance(sys.exc_info()[1], CLIENT_DISCONNECTS):
            return
        super().handle_error(request, client_address)  # type: ignore[misc]

"""The command-line side shared by the test servers' ``python -m`` entry points.

:mod:`povagent.testing.loopback_server` and :mod:`povagent.testing.hub_server` both take a
``--port`` and bind 127.0.0.1; this module reads that option and turns a failed bind into one
line a user can act on ("port 8000 in use (try --port 0 or another port)") instead of a
traceback. It must not start servers or know what they serve.
"""

from __future__ import annotations

import argparse
import errno

#: The largest TCP port number.
MAX_PORT = 65535


def port_number(text: str) -> int:
    """An argparse ``type``: a TCP port, 0 (any free port) to 65535."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (0 to {MAX_PORT}; 0: any free port)") from None
    if not 0 <= port <= MAX_PORT:
        raise argparse.ArgumentTypeError(f"{port} is not a port number (0 to {MAX_PORT}; 0: any free port)")
    return port


def bind_failure(port: int, exc: OSError) -> str:
    """What to tell the user when binding 127.0.0.1:``port`` failed with ``exc``."""
    if exc.errno == errno.EADDRINUSE:
        return f"port {port} in use (try --port 0 for any free port, or another port)"
    if exc.errno == errno.EACCES:
        return f"port {port}: permission denied (ports below 1024 need privileges; try --port 0 or a port above 1023)"
    return f"cannot listen on 127.0.0.1:{port}: {exc.strerror or exc} (try --port 0 for any free port)"

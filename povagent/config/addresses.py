"""Addresses a config names, read as values: ``host:port`` to bind a server to.

Pure parsing at the bottom of the tree, so a config is checked (and a bad value refused, naming
it) without importing the server that will later bind there.
"""

from __future__ import annotations


def parse_bind(bind: str) -> tuple[str, int]:
    """``"host:port"`` (``"[::1]:8765"`` for IPv6) as ``(host, port)``; a ValueError says what is wrong."""
    host, sep, port = bind.rpartition(":")
    if not sep or not host:
        raise ValueError(f"bind {bind!r} must be host:port, e.g. 127.0.0.1:8765")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    try:
        number = int(port)
    except ValueError:
        raise ValueError(f"bind {bind!r}: port {port!r} is not a number") from None
    if not 0 <= number <= 65535:
        raise ValueError(f"bind {bind!r}: port {number} is outside 0-65535")
    return host, number

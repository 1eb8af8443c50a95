"""The response cache: content-addressed, on disk, shared by every run and cell that points at it.

The key is the SHA-256 of the backend's identity (model and answer-changing options, never a
secret), the request's content hash (messages with image *hashes*, generation parameters) and
the run index, so re-running a finished sweep makes no model call while repeats stay
independent samples. Only successful responses are stored: an error is never cached.

One SQLite file in WAL mode: several processes may read and write it at once, a crash loses at
most the last uncommitted answer, and a corrupt or foreign file is reported, not trusted.
This module must not decide *whether* to cache (the runner does, from ``Backend.cacheable``).
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any, Mapping

from povagent.errors import PovagentError
from povagent.exchange import Response, Usage

SCHEMA_VERSION = 1


def identity_json(backend_identity: Mapping[str, Any]) -> str:
    """Canonical JSON of a backend identity (compute once per run, reuse per request)."""
    return json.dumps(backend_identity, sort_keys=True, separators=(",", ":"), default=str)


def cache_key(backend_identity: Mapping[str, Any] | str, request_hash: str, run: int) -> str:
    """The cache key of one model call (hex SHA-256).

    ``backend_identity`` is the backend's identity, or its :func:`identity_json` computed once.
    """
    blob = backend_identity if isinstance(backend_identity, str) else identity_json(backend_identity)
    h = hashlib.sha256()
    h.update(f"povagent-cache-v{SCHEMA_VERSION}\x00".encode())
    h.update(blob.encode())
    h.update(f"\x00{request_hash}\x00{run}".encode())
    return h.hexdigest()


class CacheError(PovagentError):
    """The cache file cannot be used (not a povagent cache, or corrupt)."""


class ResponseCache:
    """Responses by key in one SQLite file (thread-safe; safe across processes via WAL)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.hits = 0
        self.misses = 0
        self.writes = 0
        self._lock = threading.Lock()
        try:
            self._db = sqlite3.connect(self.path, check_same_thread=False, timeout=30.0, isolation_level=None)
            self._db.execute("PRAGMA journal_mode=WAL")
            # NORMAL in WAL: a power cut may lose the last answers, never corrupt the file;
            # a lost answer just costs one more call.
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.execute(
                "CREATE TABLE IF NOT EXISTS responses ("
                " key TEXT PRIMARY KEY, text TEXT NOT NULL, usage TEXT NOT NULL,"
                " model TEXT, latency_s REAL NOT NULL, created REAL NOT NULL)"
            )
        except sqlite3.DatabaseError as exc:
            raise CacheError(f"{self.path}: cannot be used as a response cache ({exc}); delete it or choose another cache path") from None

    def get(self, key: str) -> Response | None:
        """The cached response for ``key`` (marked ``cached=True``), or ``None``."""
        with self._lock:
            row = self._db.execute("SELECT text, usage, model, latency_s FROM responses WHERE key = ?", (key,)).fetchone()
        if row is None:
            self.misses += 1
            return None
        self.hits += 1
        text, usage, model, latency = row
        u = json.loads(usage)
        return Response(
            text=text,
            usage=Usage(u.get("prompt_tokens"), u.get("completion_tokens"), u.get("cost_usd")),
            latency_s=latency,
            model=model,
            cached=True,
        )

    def put(self, key: str, response: Response) -> None:
        """Store a successful response (the caller never passes an error)."""
        usage = json.dumps(
            {"prompt_tokens": response.usage.prompt_tokens, "completion_tokens": response.usage.completion_tokens, "cost_usd": response.usage.cost_usd}
        )
        with self._lock:
            self._db.execute(
                "INSERT OR REPLACE INTO responses (key, text, usage, model, latency_s, created) VALUES (?, ?, ?, ?, ?, ?)",
                (key, response.text, usage, response.model, response.latency_s, time.time()),
            )
        self.writes += 1

    def __len__(self) -> int:
        with self._lock:
            return int(self._db.execute("SELECT COUNT(*) FROM responses").fetchone()[0])

    def close(self) -> None:
        """Close the database."""
        with self._lock:
            self._db.close()

    def __enter__(self) -> "ResponseCache":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

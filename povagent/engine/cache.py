"""The response cache: content-addressed, on disk, shared by every run and cell that points at it.

The key is the SHA-256 of the backend's identity (model and answer-changing options, never a
secret), the request's content hash (messages with image *hashes*, generation parameters) and
the run index, so re-running a finished sweep makes no model call while repeats stay
independent samples. Only successful responses are stored: an error is never cached.

One SQLite file in WAL mode: several processes may read and write it at once, a crash loses at
most the last uncommitted answers, and a corrupt or foreign file is reported, not trusted.
:meth:`ResponseCache.put` stores at once; :meth:`ResponseCache.put_deferred` queues (visible to
:meth:`ResponseCache.get` at once) for :meth:`ResponseCache.flush`, which writes the queue in one
transaction on its own connection, so a caller can keep writes off its event loop: the runner
flushes from its row-writing thread before each batch of rows, so an answer is stored before
the row that holds it is durable. Reads use a connection of their own (WAL readers never wait
for a writer). This module must not decide *whether* to cache (the runner does, from
``Backend.cacheable``).
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any, Iterable, Mapping

from povagent.errors import PovagentError
from povagent.exchange.messages import Response, Usage

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

    def __init__(self, path: str | Path, *, read_also: str | Path | None = None) -> None:
        """Open (or create) the cache at ``path``.

        ``read_also``: another cache file that :meth:`get` consults, read-only, when ``path`` has
        no answer (a shard reading its sweep's cache). A file that is missing or unusable there
        is passed over: the cache only saves calls.
        """
        self.path = Path(path)
        self._read_also = Path(read_also) if read_also is not None else None
        self._rdb: sqlite3.Connection | None = None
        from povagent.files.confined_write import ConfinedFolder

        # SQLite opens its files by path, following links: one planted as the cache (or its
        # journal) in a run folder would have answers written into a file elsewhere.
        with ConfinedFolder(self.path.parent) as folder:
            for name in (self.path.name, self.path.name + "-wal", self.path.name + "-shm", self.path.name + "-journal"):
                folder.check_plain_file(name)
        self.hits = 0
        self.misses = 0
        self.writes = 0
        self._lock = threading.Lock()  # the read connection
        self._write_lock = threading.Lock()  # the write connection
        self._pending_lock = threading.Lock()
        #: Responses queued by put_deferred(), by key: (key, text, usage, model, latency_s, created),
        #: the usage as read (serialized when written, off the caller's loop).
        self._pending: dict[str, tuple[str, str, Usage, str | None, float, float]] = {}
        self._db: sqlite3.Connection | None = None
        self._wdb: sqlite3.Connection | None = None
        try:
            self._wdb = self._connect()
            self._wdb.execute("PRAGMA journal_mode=WAL")
            self._wdb.execute(
                "CREATE TABLE IF NOT EXISTS responses ("
                " key TEXT PRIMARY KEY, text TEXT NOT NULL, usage TEXT NOT NULL,"
                " model TEXT, latency_s REAL NOT NULL, created REAL NOT NULL)"
            )
            self._db = self._connect()
            self._db.execute("SELECT 1 FROM responses LIMIT 1").fetchall()
        except sqlite3.DatabaseError as exc:
            for db in (self._db, self._wdb):
                if db is not None:
                    db.close()
            raise CacheError(f"{self.path}: cannot be used as a response cache ({exc}); delete it or choose another cache path") from None

    def _connect(self) -> sqlite3.Connection:
        db = sqlite3.connect(self.path, check_same_thread=False, timeout=30.0, isolation_level=None)
        # NORMAL in WAL: a power cut may lose the last answers, never corrupt the file;
        # a lost answer just costs one more call.
        db.execute("PRAGMA synchronous=NORMAL")
        return db

    def get(self, key: str) -> Response | None:
        """The cached response for ``key`` (marked ``cached=True``), or ``None``.

        A response queued by :meth:`put_deferred` and not yet flushed is found too.
        """
        pending = self._pending.get(key)
        if pending is not None:
            self.hits += 1
            _, text, u, model, latency, _ = pending
            return Response(text=text, usage=Usage(u.prompt_tokens, u.completion_tokens, u.cost_usd), latency_s=latency, model=model, cached=True)
        with self._lock:
            # the connection is None only after close()
            row = self._db.execute("SELECT text, usage, model, latency_s FROM responses WHERE key = ?", (key,)).fetchone()  # type: ignore[union-attr]
            if row is None and self._read_also is not None:
                row = self._read_other(key)
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

    def _read_other(self, key: str) -> Any:
        """``key``'s row in the ``read_also`` file, or ``None`` (called under the read lock)."""
        other = self._read_also
        assert other is not None
        try:
            if self._rdb is None:
                if not other.is_file():
                    self._read_also = None  # written by the client only after the cells: not now
                    return None
                self._rdb = sqlite3.connect(f"{other.resolve().as_uri()}?mode=ro", uri=True, check_same_thread=False, timeout=30.0)
            return self._rdb.execute("SELECT text, usage, model, latency_s FROM responses WHERE key = ?", (key,)).fetchone()
        except sqlite3.Error:
            self._read_also = None  # not a cache, or unreadable from here: answers come from the model
            return None

    @staticmethod
    def _record(key: str, response: Response) -> tuple[str, str, Usage, str | None, float, float]:
        u = response.usage
        return (key, response.text, Usage(u.prompt_tokens, u.completion_tokens, u.cost_usd), response.model, response.latency_s, time.time())

    def _insert(self, records: list[tuple[str, str, Usage, str | None, float, float]]) -> None:
        """Write ``records`` in one transaction."""
        rows = [
            (key, text, json.dumps({"prompt_tokens": u.prompt_tokens, "completion_tokens": u.completion_tokens, "cost_usd": u.cost_usd}),
             model, latency, created)
            for key, text, u, model, latency, created in records
        ]
        with self._write_lock:
            db = self._wdb
            assert db is not None, "cache closed"
            db.execute("BEGIN")
            try:
                db.executemany(
                    "INSERT OR REPLACE INTO responses (key, text, usage, model, latency_s, created) VALUES (?, ?, ?, ?, ?, ?)",
                    rows,
                )
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT")
            self.writes += len(records)

    def put(self, key: str, response: Response) -> None:
        """Store a successful response now (the caller never passes an error)."""
        self._insert([self._record(key, response)])

    def put_deferred(self, key: str, response: Response) -> None:
        """Queue a successful response (the caller never passes an error) for :meth:`flush`.

        :meth:`get` finds it at once; it is on disk after the next :meth:`flush` (or
        :meth:`close`). The response's fields are read now.
        """
        record = self._record(key, response)
        with self._pending_lock:
            self._pending[key] = record

    @property
    def pending(self) -> int:
        """How many queued responses are not yet written."""
        return len(self._pending)

    def flush(self) -> int:
        """Write the queued responses in one transaction (safe from any thread); returns how
        many. A response stays visible to :meth:`get` until it is written; if writing fails,
        the error is raised and the responses stay queued."""
        with self._pending_lock:
            batch = list(self._pending.values())
        if not batch:
            return 0
        self._insert(batch)
        with self._pending_lock:
            for record in batch:
                if self._pending.get(record[0]) is record:
                    del self._pending[record[0]]
        return len(batch)

    def discard_pending(self) -> int:
        """Drop the queued responses without writing them (after a failed :meth:`flush`)."""
        with self._pending_lock:
            n = len(self._pending)
            self._pending.clear()
        return n

    def __len__(self) -> int:
        self.flush()
        with self._lock:
            return int(self._db.execute("SELECT COUNT(*) FROM responses").fetchone()[0])  # type: ignore[union-attr]  # None only after close()

    def close(self) -> None:
        """Write what is queued, then close the database."""
        try:
            self.flush()
        finally:
            with self._write_lock:
                if self._wdb is not None:
                    self._wdb.close()
            with self._lock:
                if self._db is not None:
                    self._db.close()
                if self._rdb is not None:
                    self._rdb.close()

    def __enter__(self) -> ResponseCache:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def merge_shards(cache: ResponseCache, shards: Iterable[Path]) -> tuple[int, list[str]]:
    """Fold shard files into ``cache`` and delete them: ``(answers added, problems)``.

    An answer already in ``cache`` is kept (keys are content hashes; the rows hold what was
    used). Each shard is copied in one transaction and deleted only after it committed, so a
    kill at any moment leaves it to be merged again, harmlessly. A shard that is not a usable
    cache is left in place and named in ``problems`` (it only held answers, never rows).
    """
    added, problems = 0, []
    cache.flush()
    for shard in shards:
        if not shard.is_file():
            continue
        with cache._write_lock:
            db = cache._wdb
            assert db is not None, "cache closed"
            try:
                db.execute("ATTACH DATABASE ? AS shard", (str(shard),))
            except sqlite3.Error as exc:
                problems.append(f"{shard}: not merged into {cache.path} ({exc})")
                continue
            try:
                db.execute("BEGIN")
                before = db.total_changes
                db.execute(
                    "INSERT OR IGNORE INTO main.responses (key, text, usage, model, latency_s, created)"
                    " SELECT key, text, usage, model, latency_s, created FROM shard.responses"
                )
                changed = db.total_changes - before
                db.execute("COMMIT")
            except sqlite3.Error as exc:
                if db.in_transaction:
                    db.execute("ROLLBACK")
                problems.append(f"{shard}: not merged into {cache.path} ({exc})")
                continue
            finally:
                db.execute("DETACH DATABASE shard")
        added += changed
        cache.writes += changed
        for suffix in ("", "-wal", "-shm"):
            Path(f"{shard}{suffix}").unlink(missing_ok=True)
    return added, problems

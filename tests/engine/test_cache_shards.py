"""Cache shards: several processes write their own shard at once while reading the sweep's
cache; the client folds them in, every answer once, and a second fold changes nothing."""

from __future__ import annotations

import multiprocessing
import sqlite3
from pathlib import Path
from typing import Any

from povagent.engine.cache import ResponseCache, merge_shards
from povagent.exchange.messages import Response, Usage

WRITERS = 3
SHARED = 60  # keys every writer answers (a request common to several cells)
OWN = 60  # keys only one writer answers


def _answer(key: str) -> Response:
    return Response(f"answer to {key}", Usage(10, 2, 0.001), latency_s=0.1, model="m")


def _write_shard(main: str, shard: str, writer: int, start: Any) -> None:
    """A cell on a worker: reads the sweep's cache, stores what it did not find in its shard."""
    start.wait(30)
    with ResponseCache(shard, read_also=main) as cache:
        for i in range(SHARED + OWN):
            key = f"shared-{i}" if i < SHARED else f"own-{writer}-{i}"
            if cache.get(key) is None:
                # batches as the runner writes them: queued, then flushed with a batch of rows
                cache.put_deferred(key, _answer(key))
                if i % 7 == 0:
                    cache.flush()


def test_shards_written_by_several_processes_at_once_merge_into_one_cache(tmp_path) -> None:
    main = tmp_path / "cache.sqlite"
    with ResponseCache(main) as cache:  # the sweep's cache already knows half the shared keys
        for i in range(SHARED // 2):
            cache.put(f"shared-{i}", _answer(f"shared-{i}"))
    shards = [tmp_path / f"cell{w}" / "cache-shard.sqlite" for w in range(WRITERS)]
    ctx = multiprocessing.get_context("spawn")
    start = ctx.Event()
    procs = [ctx.Process(target=_write_shard, args=(str(main), str(s), w, start)) for w, s in enumerate(shards)]
    for p in procs:
        p.start()
    start.set()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    # a shard holds only what its cell did not find in the sweep's cache
    for shard in shards:
        with ResponseCache(shard) as one:
            assert len(one) == SHARED // 2 + OWN
    with ResponseCache(main) as cache:
        added, problems = merge_shards(cache, shards)
        assert problems == [] and added == SHARED // 2 + WRITERS * OWN
        assert len(cache) == SHARED + WRITERS * OWN
        for key in ["shared-0", f"shared-{SHARED - 1}", f"own-2-{SHARED + OWN - 1}"]:
            hit = cache.get(key)
            assert hit is not None and hit.text == f"answer to {key}" and hit.usage.cost_usd == 0.001
        assert not any(Path(f"{s}{x}").exists() for s in shards for x in ("", "-wal", "-shm"))
        assert merge_shards(cache, shards) == (0, [])  # nothing left: harmless


def test_a_shard_reads_the_sweeps_cache_beside_it(tmp_path) -> None:
    with ResponseCache(tmp_path / "main.sqlite") as main:
        main.put("k", _answer("k"))
        with ResponseCache(tmp_path / "shard.sqlite", read_also=tmp_path / "main.sqlite") as shard:
            hit = shard.get("k")  # found while the sweep's cache is open elsewhere
            assert hit is not None and hit.cached and hit.text == "answer to k"
            assert len(shard) == 0  # reading never copies into the shard


def test_a_missing_or_foreign_file_beside_is_passed_over(tmp_path) -> None:
    (tmp_path / "foreign.sqlite").write_bytes(b"not a database at all" * 100)
    for other in (tmp_path / "absent.sqlite", tmp_path / "foreign.sqlite"):
        with ResponseCache(tmp_path / f"shard-{other.stem}.sqlite", read_also=other) as shard:
            assert shard.get("k") is None and shard.get("k") is None


def test_a_shard_that_is_not_a_cache_is_named_and_kept(tmp_path) -> None:
    bad = tmp_path / "cell" / "cache-shard.sqlite"
    bad.parent.mkdir()
    db = sqlite3.connect(bad)
    db.execute("CREATE TABLE other (x)")
    db.commit()
    db.close()
    good = tmp_path / "good.sqlite"
    with ResponseCache(good) as shard:
        shard.put("g", _answer("g"))
    with ResponseCache(tmp_path / "main.sqlite") as cache:
        added, problems = merge_shards(cache, [bad, good])
        assert added == 1 and len(problems) == 1 and str(bad) in problems[0]
        assert bad.exists() and not good.exists()

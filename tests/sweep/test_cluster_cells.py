"""What a sweep hands a cluster: each cell's pipeline with absolute paths, nothing else changed."""

from __future__ import annotations

import os
import pickle
from pathlib import Path

import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.sweep import anchored


def test_a_cell_sent_to_a_worker_has_absolute_paths_and_the_same_pipeline(tmp_path, monkeypatch, mini_root) -> None:
    monkeypatch.chdir(tmp_path)
    os.symlink(mini_root, tmp_path / "mini")
    (tmp_path / "p.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": "mini"}, "model": "gpt-5.4", "output": "runs/cell",
        "cache": "runs/cache.sqlite", "images": {"transport": "file", "cache_dir": "frames"},
    }))
    config = load_pipeline(tmp_path / "p.yaml")
    assert config.model == "gpt-5.4" and config.backend is not None  # a profile resolved: both set
    sent = pickle.loads(pickle.dumps(anchored(config)))  # as the worker receives it
    assert sent.output == tmp_path / "runs" / "cell" and sent.dataset.path == tmp_path / "mini"
    assert sent.cache.path == tmp_path / "runs" / "cache.sqlite" and sent.images.cache_dir == tmp_path / "frames"
    assert sent.config_hash() == config.config_hash() and sent.model == config.model
    assert sent.backend == config.backend and sent.parser == config.parser
    assert all(Path(p).is_absolute() for p in (sent.output, sent.dataset.path))


def test_a_cells_cache_shard_is_merged_only_when_no_one_runs_the_cell(tmp_path) -> None:
    from types import SimpleNamespace

    from povagent.engine.cache import ResponseCache
    from povagent.exchange.messages import Response, Usage
    from povagent.files.folder_lock import folder_lock
    from povagent.run.sweep import CELL_CACHE_SHARD, _merge_cell_caches

    run_dir = tmp_path / "cell"
    run_dir.mkdir()
    with ResponseCache(run_dir / CELL_CACHE_SHARD) as shard:
        shard.put("k", Response("answer", Usage(1, 1, None), latency_s=0.1))
    cell = SimpleNamespace(config=SimpleNamespace(output=run_dir))
    main = tmp_path / "cache.sqlite"
    with folder_lock(run_dir):  # a worker still runs the cell, writing its shard
        _merge_cell_caches(main, [cell], print)  # type: ignore[list-item]
    assert (run_dir / CELL_CACHE_SHARD).is_file()
    with ResponseCache(main) as cache:
        assert cache.get("k") is None
    _merge_cell_caches(main, [cell], print)  # type: ignore[list-item]
    assert not (run_dir / CELL_CACHE_SHARD).exists()
    with ResponseCache(main) as cache:
        hit = cache.get("k")
        assert hit is not None and hit.text == "answer"

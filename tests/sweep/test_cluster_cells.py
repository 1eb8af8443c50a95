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

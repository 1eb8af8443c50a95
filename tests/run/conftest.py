"""Runner test fixtures: a small synthetic release and pipeline YAMLs using the offline test plugin."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from povagent.testing.pytest_plugin import write_release


@pytest.fixture(scope="session")
def small_release(tmp_path_factory) -> Path:
    """2 houses, 2 pairs, 4 (pair, direction)s, 3 frames: 12 instances over the 3 conditions."""
    return write_release(tmp_path_factory.mktemp("release") / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)


@pytest.fixture
def offline_plugin(offline_plugin_file):
    """The offline test plugin module, as loaded from its copy beside the test's pipelines
    (``module.__file__``; shared with subprocesses)."""
    from povagent.plugins import _import_module_or_file

    module = _import_module_or_file(str(offline_plugin_file))
    module.CALLS["count"] = 0
    module.FlakyBackend.SCRIPT.clear()
    return module


@pytest.fixture
def write_pipeline(tmp_path, small_release, povagent_host, offline_plugin):
    """``write_pipeline(**overrides) -> Path``: a pipeline YAML over the small release."""

    def make(name: str = "pipeline.yaml", **overrides: Any) -> Path:
        data: dict[str, Any] = {
            "plugins": [offline_plugin.__file__],
            "dataset": {"path": str(small_release)},
            "backend": {"name": "test-center"},
            "strategy": "test-point",
            "parser": "test-json",
            "scorers": ["official"],
            "runs": 1,
            "concurrency": 4,
            "retry": {"attempts": 3, "initial_wait": 0.0, "max_wait": 0.01},
            "timeout": 5,
            "output": str(tmp_path / "run"),
        }
        data.update(overrides)
        path = tmp_path / name
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return make

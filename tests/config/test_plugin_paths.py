"""A ``.py`` path under ``plugins:`` is read from the YAML file's folder, not the working directory,
and never from outside it (see also ``test_plugin_rule.py``)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError

PLUGIN = '''
from povagent import hookimpl
from povagent.interfaces import Strategy


class Shout(Strategy):
    def build(self, instance, images):
        raise NotImplementedError


@hookimpl
def register_strategies(register):
    register("shout-{tag}", Shout, description="a throwaway strategy")
'''


def write(folder: Path, tag: str, mini_root: Path, plugin_entry: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "my_plugin.py").write_text(PLUGIN.replace("{tag}", tag))
    path = folder / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "plugins": [plugin_entry],
        "dataset": str(mini_root),
        "backend": "center",
        "strategy": f"shout-{tag}",
        "output": "run",
    }))
    return path


def test_a_relative_plugin_path_is_read_from_the_yaml_folder(tmp_path, mini_root, monkeypatch):
    path = write(tmp_path / "project" / "configs", "here", mini_root, "my_plugin.py")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the working directory holds no my_plugin.py
    config = load_pipeline(path)
    assert config.strategy.name == "shout-here"
    assert Path(config.plugins[0]) == path.parent / "my_plugin.py"


def test_a_plugin_path_climbing_out_of_the_yaml_folder_is_refused(tmp_path, mini_root, monkeypatch):
    path = write(tmp_path / "project" / "configs", "up", mini_root, "../plugins/my_plugin.py")
    (tmp_path / "project" / "plugins").mkdir()
    os.replace(path.parent / "my_plugin.py", tmp_path / "project" / "plugins" / "my_plugin.py")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=r"line \d+: plugin '../plugins/my_plugin.py' is a path outside the config's folder"):
        load_pipeline(path)


def test_a_sweeps_base_pipeline_reads_its_plugin_path_from_its_own_folder(tmp_path, mini_root, monkeypatch, povagent_host):
    from povagent.run.sweep import expand_sweep

    base = write(tmp_path / "project" / "configs", "swept", mini_root, "my_plugin.py")
    sweep = tmp_path / "project" / "sweep.yaml"  # one folder above its base
    sweep.write_text(yaml.safe_dump({"base": "configs/pipeline.yaml", "output": "runs", "axes": {"backend": ["center", "random"]}}))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    _, cells = expand_sweep(sweep)
    assert [c.config.strategy.name for c in cells] == ["shout-swept", "shout-swept"]
    assert {Path(p) for c in cells for p in c.config.plugins} == {base.parent / "my_plugin.py"}

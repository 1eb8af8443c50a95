"""Commands that read a pipeline YAML accept ``dataset: {hub: ...}`` and fetch it first."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.testing.hub_server import HubServer


def test_show_prompt_fetches_a_hub_dataset_first(tmp_path, mini_root, monkeypatch):
    monkeypatch.delenv("HF_HUB_OFFLINE", raising=False)
    monkeypatch.delenv("HF_HUB_CACHE", raising=False)
    monkeypatch.setenv("HF_HOME", str(tmp_path / "hf"))
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"hub": "owl-owl/POVBench"},
        "instances": {"conditions": ["c"]},
        "backend": {"name": "center"},
        "output": str(tmp_path / "run"),
    }))  # fmt: skip
    with HubServer(mini_root, max_lifetime_s=60) as hub:
        monkeypatch.setenv("HF_ENDPOINT", hub.url)
        result = CliRunner().invoke(
            app, ["show-prompt", str(path), "--instance", "train_house_00000/0/right/c", "--out", str(tmp_path / "shown")]
        )
    assert result.exit_code == 0, result.output
    assert "artifacts/train_house_00000/img_from_observer/pair_0.png" in hub.fetched_files()
    assert not any("exploration_images/" in f for f in hub.fetched_files())

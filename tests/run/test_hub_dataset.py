"""A pipeline naming ``dataset: {hub: ...}`` runs on the release fetched from a loopback Hub."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.hub_server import HubServer


@pytest.fixture
def hub(small_release, monkeypatch, tmp_path):
    """The small synthetic release served as owl-owl/POVBench; the cache lives in tmp_path."""
    monkeypatch.delenv("HF_HUB_OFFLINE", raising=False)
    monkeypatch.delenv("HF_HUB_CACHE", raising=False)
    monkeypatch.setenv("HF_HOME", str(tmp_path / "hf"))
    with HubServer(small_release, max_lifetime_s=60) as server:
        monkeypatch.setenv("HF_ENDPOINT", server.url)
        yield server


def test_a_given_only_run_fetches_no_frame_and_records_the_commit(write_pipeline, hub, tmp_path):
    path = write_pipeline(dataset={"hub": "owl-owl/POVBench"}, instances={"conditions": ["c"]})
    result = run_pipeline(load_pipeline(path))
    rows = read_rows(result.run_dir / "results.jsonl")
    assert rows and {r.condition for r in rows} == {"c"} and all(r.status == "answered" for r in rows)
    assert not any("exploration_images/" in f for f in hub.fetched_files())
    recorded = yaml.safe_load((result.run_dir / "config.yaml").read_text())["dataset"]
    assert recorded["hub"] == "owl-owl/POVBench" and recorded["revision"] == hub.commit
    assert recorded["path"].startswith(str(tmp_path / "hf" / "hub"))


def test_a_run_resumes_offline_from_its_config_yaml(write_pipeline, hub, monkeypatch):
    path = write_pipeline(dataset={"hub": "owl-owl/POVBench"}, instances={"conditions": ["a"], "limit": 2})
    first = run_pipeline(load_pipeline(path))
    hub.stop()
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    # the recorded config, saved beside the pipeline (a run folder's config.yaml loads no plugin)
    again_yaml = path.parent / "again.yaml"
    again_yaml.write_text((first.run_dir / "config.yaml").read_text())
    config = load_pipeline(again_yaml)
    config.instances.limit = 4
    again = run_pipeline(config)
    assert again.n_pending == 2 and len(read_rows(again.run_dir / "results.jsonl")) == 4


def test_every_sweep_cell_runs_on_the_fetched_release_and_records_it(hub, tmp_path, offline_plugin):
    from povagent.run.sweep import run_sweep

    base = {
        "plugins": [offline_plugin.__file__], "dataset": {"hub": "owl-owl/POVBench"}, "backend": {"name": "test-center"},
        "strategy": "test-point", "parser": "test-json", "concurrency": 4, "output": "ignored-by-sweeps",
    }  # fmt: skip
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"base: base.yaml\noutput: {tmp_path / 'sweep'}\naxes:\n  conditions: [c, a]\n")
    result = run_sweep(sweep, quiet=True)
    for cell in result.cells:
        recorded = yaml.safe_load((cell.config.output / "config.yaml").read_text())["dataset"]
        assert recorded["revision"] == hub.commit and recorded["path"].startswith(str(tmp_path / "hf"))
        assert read_rows(cell.config.output / "results.jsonl")

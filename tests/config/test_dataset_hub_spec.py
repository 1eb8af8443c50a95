"""``dataset: {hub: ..., revision: ...}`` in a pipeline YAML: what is accepted, what is refused."""

from __future__ import annotations

import textwrap

import pytest

from povagent.config.pipeline import dump_pipeline, load_pipeline
from povagent.errors import ConfigError

REST = """\
backend: {name: center}
output: runs/x
"""


def pipeline(tmp_path, dataset: str):
    path = tmp_path / "pipeline.yaml"
    path.write_text(textwrap.dedent(dataset) + REST)
    return load_pipeline(path)


def test_a_hub_repository_with_a_revision_is_a_dataset(tmp_path):
    config = pipeline(tmp_path, "dataset: {hub: owl-owl/POVBench, revision: v1.0}\n")
    assert config.dataset.hub == "owl-owl/POVBench" and config.dataset.revision == "v1.0"
    assert config.dataset.path is None and config.dataset.generate is None


def test_the_revision_is_optional(tmp_path):
    assert pipeline(tmp_path, "dataset: {hub: owl-owl/POVBench}\n").dataset.revision is None


def test_a_revision_without_a_repository_is_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"dataset.revision needs dataset.hub"):
        pipeline(tmp_path, "dataset: {path: data/povbench, revision: main}\n")


def test_hub_and_generate_together_are_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"exactly one of dataset.path, dataset.generate or dataset.hub"):
        pipeline(tmp_path, "dataset: {hub: owl-owl/POVBench, generate: {out: data/gen}}\n")


def test_a_repository_id_is_owner_slash_name(tmp_path):
    with pytest.raises(ConfigError, match=r"dataset.hub"):
        pipeline(tmp_path, "dataset: {hub: POVBench}\n")


def test_a_resolved_hub_dataset_round_trips_through_config_yaml(tmp_path):
    # a run writes hub, the pinned commit and the local copy; reading that config.yaml back works
    config = pipeline(tmp_path, f"dataset: {{hub: owl-owl/POVBench, revision: '{'a' * 40}', path: /data/snap}}\n")
    dumped = dump_pipeline(config)
    (tmp_path / "config.yaml").write_text(dumped)
    again = load_pipeline(tmp_path / "config.yaml")
    assert again.dataset == config.dataset and str(again.dataset.root) == "/data/snap"


def test_download_bounds_are_keys_of_a_hub_dataset(tmp_path):
    config = pipeline(tmp_path, "dataset: {hub: owl-owl/POVBench, download: {deadline_s: 60, max_file_mib: 8}}\n")
    limits = config.dataset.download
    assert limits.deadline_s == 60 and limits.max_file_bytes == 8 * 2**20 and limits.max_total_mib == 4096


@pytest.mark.parametrize(
    "download,match",
    [("{deadline_s: 0}", "greater than 0"), ("{max_total_mib: -1}", "greater than 0"), ("{deadline: 5}", "deadline")],
)
def test_download_bounds_out_of_range_or_misspelled_are_refused(tmp_path, download, match):
    with pytest.raises(ConfigError, match=match):
        pipeline(tmp_path, f"dataset: {{hub: owl-owl/POVBench, download: {download}}}\n")


def test_download_bounds_without_a_hub_are_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"dataset.download needs dataset.hub"):
        pipeline(tmp_path, "dataset: {path: data/povbench, download: {deadline_s: 5}}\n")


@pytest.mark.parametrize("revision", ["../../../venv/site-packages/evil.pth", "/abs", "a//b", ".hidden"])
def test_a_revision_that_could_leave_the_cache_is_refused_when_the_config_is_read(tmp_path, revision):
    with pytest.raises(ConfigError, match=r"dataset.revision"):
        pipeline(tmp_path, f"dataset: {{hub: owl-owl/POVBench, revision: '{revision}'}}\n")

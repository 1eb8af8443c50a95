"""Fetching the release from the Hub: real huggingface_hub downloads from a loopback Hub.

Every test points huggingface_hub at a :class:`HubServer` on 127.0.0.1 serving the hand-made
release, and at a cache under ``tmp_path``: nothing here reaches the network or the user's
Hugging Face cache.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.config.pipeline import resolve_hub_dataset
from povagent.dataset.hub import (
    RELEASE_REPO,
    download_release,
    find_release_root,
    parse_conditions,
    release_patterns,
)
from povagent.dataset.loader import load_dataset
from povagent.dataset.release_models import Condition
from povagent.errors import DatasetError
from povagent.testing.hub_server import HubServer


def release_files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


@pytest.fixture
def hub(mini_root, monkeypatch, tmp_path):
    """The hand-made release served as owl-owl/POVBench; HF_* variables point at it and at a
    cache in tmp_path (read by povagent at each call, so in-process tests see them)."""
    monkeypatch.delenv("HF_HUB_OFFLINE", raising=False)
    monkeypatch.delenv("TRANSFORMERS_OFFLINE", raising=False)
    monkeypatch.delenv("HF_HUB_CACHE", raising=False)
    monkeypatch.setenv("HF_HOME", str(tmp_path / "hf"))
    with HubServer(mini_root, repo_id=RELEASE_REPO, revisions=("main", "v1.0"), max_lifetime_s=60) as server:
        monkeypatch.setenv("HF_ENDPOINT", server.url)
        yield server


# -- what each condition fetches ------------------------------------------------------------------
def test_all_conditions_fetch_the_whole_repository():
    assert release_patterns(None) == (None, None)
    assert release_patterns(["a", "b", "c"]) == (None, None)


def test_condition_names_are_letters_or_the_papers_words():
    assert parse_conditions(["Given"]) == (Condition.GIVEN,)
    assert parse_conditions("stated") == (Condition.STATED,)
    assert parse_conditions(["c,a"]) == (Condition.INFERRED, Condition.GIVEN)
    with pytest.raises(DatasetError, match="'d'"):
        parse_conditions(["d"])


def test_full_download_holds_the_release_and_loads(hub, mini_root, tmp_path):
    release = download_release(progress=False)
    assert release.commit == hub.commit and release.snapshot.name == hub.commit
    assert release.root == release.snapshot  # the release sits at the repository root
    assert release_files(release.root) == release_files(mini_root)
    # the standard cache layout under HF_HOME, as every Hugging Face tool reads it
    assert release.snapshot == tmp_path / "hf" / "hub" / "datasets--owl-owl--POVBench" / "snapshots" / hub.commit
    assert set(load_dataset(release.root).houses) == set(load_dataset(mini_root).houses)


def test_given_only_fetches_no_exploration_frame(hub, mini_root):
    release = download_release(conditions=["c"], progress=False)
    fetched = set(hub.fetched_files())
    assert not any("exploration_images/" in f for f in fetched)
    assert not any(f.endswith("per_image_visible_objects.json") for f in fetched)
    # what Given reads: meta.json, each house file and log, the observer views
    expected = {
        f for f in release_files(mini_root)
        if f == "meta.json" or "img_from_observer/" in f
        or f.endswith(("exploration_log.json",)) or f.split("/")[-1] == f.split("/")[-2] + ".json"
    }  # fmt: skip
    assert fetched == expected == release_files(release.root)
    ds = load_dataset(release.root)
    given = ds.instances([Condition.GIVEN], None, None)
    assert given and all(i.frames[0].file.is_file() for i in given)


def test_inferred_and_stated_fetch_frames_but_not_observer_views(hub, mini_root):
    release = download_release(conditions=["a", "b"], progress=False)
    files = release_files(release.root)
    assert not any("img_from_observer/" in f for f in files)
    frames = {f for f in release_files(mini_root) if "exploration_images/" in f}
    assert frames <= files
    assert {f for f in release_files(mini_root) if f.endswith("per_image_visible_objects.json")} <= files


def test_a_second_download_only_checks_the_revision(hub):
    download_release(progress=False)
    n_files = len(hub.fetched_files())
    download_release(progress=False)
    assert len(hub.fetched_files()) == n_files  # nothing fetched again


def test_a_tag_and_a_commit_hash_are_revisions(hub):
    by_tag = download_release(revision="v1.0", progress=False)
    by_commit = download_release(revision=hub.commit, progress=False)
    assert by_tag.commit == by_commit.commit == hub.commit and by_tag.revision == "v1.0"


def test_explicit_endpoint_and_cache_win_over_the_environment(hub, monkeypatch, tmp_path):
    monkeypatch.setenv("HF_ENDPOINT", "http://127.0.0.1:9")  # nothing listens there
    release = download_release(endpoint=hub.url, cache_dir=tmp_path / "elsewhere", progress=False)
    assert release.snapshot.is_relative_to(tmp_path / "elsewhere")


# -- offline ----------------------------------------------------------------------------------
def test_offline_reads_the_cache_without_a_request(hub, monkeypatch):
    online = download_release(progress=False)
    hub.stop()
    n_requests = len(hub.requests)
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    offline = download_release(progress=False)
    assert offline.root == online.root and len(hub.requests) == n_requests


def test_offline_without_a_cached_copy_says_how_to_fetch_it(hub, monkeypatch):
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    with pytest.raises(DatasetError) as err:
        download_release(progress=False)
    msg = str(err.value)
    assert "owl-owl/POVBench @ main" in msg and "HF_HUB_OFFLINE" in msg and "povagent download owl-owl/POVBench" in msg


def test_offline_with_a_given_only_cache_refuses_a_run_that_needs_frames(hub):
    download_release(conditions=["c"], progress=False)
    download_release(conditions=["c"], offline=True, progress=False)  # what it holds is enough for C
    with pytest.raises(DatasetError) as err:
        download_release(conditions=["a"], offline=True, progress=False)
    msg = str(err.value)
    assert "owl-owl/POVBench @ main" in msg and "exploration_images/" in msg
    assert "povagent download owl-owl/POVBench --conditions a" in msg


# -- failures ---------------------------------------------------------------------------------
def test_a_revision_that_does_not_exist_names_repository_and_revision(hub):
    with pytest.raises(DatasetError) as err:
        download_release(revision="v9.9", progress=False)
    msg = str(err.value)
    assert msg.startswith("owl-owl/POVBench @ v9.9:") and "does not exist" in msg and hub.url in msg


def test_a_repository_that_does_not_exist_says_so(hub):
    with pytest.raises(DatasetError, match=r"owl-owl/Nope @ main: no dataset repository owl-owl/Nope"):
        download_release("owl-owl/Nope", progress=False)


def test_network_failure_without_a_cache_is_a_clear_error(hub):
    hub.stop()
    with pytest.raises(DatasetError) as err:
        download_release(progress=False)
    msg = str(err.value)
    assert "owl-owl/POVBench @ main" in msg and "cannot reach the Hub" in msg and hub.url in msg
    assert "Connect" in msg  # the cause, as the client saw it


def test_a_hub_outage_without_a_cache_is_a_clear_error(hub):
    hub.fail_status = 503
    with pytest.raises(DatasetError) as err:
        download_release(progress=False)
    msg = str(err.value)
    assert "owl-owl/POVBench @ main: the Hub at" in msg and "503 Service Unavailable" in msg and "\n" not in msg


def test_a_hub_outage_with_a_complete_cache_uses_the_cache(hub):
    online = download_release(progress=False)
    hub.fail_status = 500
    assert download_release(progress=False).root == online.root


def test_network_failure_with_a_complete_cache_uses_the_cache(hub):
    online = download_release(progress=False)
    hub.stop()
    assert download_release(progress=False).root == online.root


# -- the release root inside a snapshot ---------------------------------------------------------
def test_a_release_nested_one_folder_down_is_found(mini_root, monkeypatch, tmp_path):
    files = {f"POVBench/{p.relative_to(mini_root).as_posix()}": p.read_bytes() for p in mini_root.rglob("*") if p.is_file()}
    files["README.md"] = b"# POVBench\n"
    with HubServer(files=files, max_lifetime_s=60) as server:
        release = download_release(conditions=["c"], endpoint=server.url, cache_dir=tmp_path / "hf", progress=False)
    assert release.root == release.snapshot / "POVBench"
    assert (release.root / "meta.json").is_file() and not (release.snapshot / "README.md").exists()


def test_no_release_in_a_snapshot_is_a_clear_error(tmp_path):
    (tmp_path / "data").mkdir()
    with pytest.raises(DatasetError, match="repo @ main: no folder holding artifacts/"):
        find_release_root(tmp_path, "repo @ main")


def test_two_releases_in_a_snapshot_are_ambiguous(tmp_path):
    for name in ("v1", "v2"):
        (tmp_path / name / "artifacts").mkdir(parents=True)
    with pytest.raises(DatasetError, match="several releases"):
        find_release_root(tmp_path)


# -- pipelines ----------------------------------------------------------------------------------
def test_a_hub_pipeline_resolves_to_the_local_root_pinned_to_its_commit(hub, tmp_path):
    from povagent.config.models import PipelineConfig

    config = PipelineConfig.model_validate(
        {"dataset": {"hub": RELEASE_REPO, "revision": "v1.0"}, "instances": {"conditions": ["given"]},
         "backend": "center", "output": str(tmp_path / "run")}
    )  # fmt: skip
    resolved = resolve_hub_dataset(config, progress=False)
    assert resolved is config
    assert config.dataset.revision == hub.commit and config.dataset.hub == RELEASE_REPO
    assert (config.dataset.root / "artifacts").is_dir()
    assert not any("exploration_images/" in f for f in hub.fetched_files())


def test_a_hub_pipeline_not_resolved_yet_has_no_root(tmp_path):
    from povagent.config.models import DatasetSpec

    with pytest.raises(DatasetError, match=r"dataset\.hub owl-owl/POVBench: not fetched yet"):
        DatasetSpec(hub=RELEASE_REPO).root  # noqa: B018 - the property raises


def test_a_pipeline_without_hub_is_left_alone(tmp_path, mini_root):
    from povagent.config.models import PipelineConfig

    config = PipelineConfig.model_validate({"dataset": {"path": str(mini_root)}, "backend": "center", "output": str(tmp_path)})
    before = config.model_dump()
    assert resolve_hub_dataset(config).model_dump() == before


def test_a_listed_file_the_server_will_not_send_is_named(hub):
    from povagent.testing.hub_server import HubLies

    hub.lies = HubLies(missing={"meta.json"})
    with pytest.raises(DatasetError) as err:
        download_release(progress=False)
    msg = str(err.value)
    assert msg.startswith("owl-owl/POVBench @ main:") and "'meta.json'" in msg and "HTTP 404" in msg and "\n" not in msg

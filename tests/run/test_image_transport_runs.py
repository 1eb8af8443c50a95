"""Image transport through whole runs (config -> runner -> litellm -> loopback model server).

Requests, the cache key and rows name images by hash whatever the transport, so a run
restarted with another transport resumes from the cache with zero new requests; a hosted
provider is refused ``file``/``http`` before the run folder is touched; derived images (O-Plot
markers) travel by reference from the cache folder; the static server stops with the run.
"""

from __future__ import annotations

import hashlib
import socket
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, RecordedRequest

pytestmark = pytest.mark.timeout(120)

N_INSTANCES = 18  # the hand-made dataset's two good houses


def answer_for(request: RecordedRequest) -> str:
    images = [p for p in request.user_parts() if p.get("type") == "image_url"]
    return '{"selected_image": 1, "x": 300, "y": 280}' if len(images) > 1 else '{"x": 200, "y": 310}'


@pytest.fixture
def api_key(monkeypatch) -> str:
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-transport")
    return "sk-test-transport"


@pytest.fixture
def model_server(mini_root, tmp_path):
    # like vLLM with --allowed-local-media-path covering the dataset and the run folders
    common = Path(*_common_parts(mini_root.resolve(), tmp_path.resolve()))
    with LoopbackServer(reply=answer_for, fetch_images=True, local_media_root=common, max_lifetime_s=110) as server:
        yield server


def _common_parts(a: Path, b: Path) -> tuple[str, ...]:
    parts = []
    for x, y in zip(a.parts, b.parts):
        if x != y:
            break
        parts.append(x)
    return tuple(parts)


def write_pipeline(tmp_path: Path, mini_root: Path, server: LoopbackServer, *, output: str, images: dict | None = None,
                   strategy: str = "basic", model: str = "openai/loopback-vlm") -> Path:
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "litellm", "options": {"model": model, "api_base": server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
        "strategy": strategy,
        "parser": "json",
        "concurrency": 4,
        "retry": {"attempts": 2, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 20,
        "cache": str(tmp_path / "cache.sqlite"),
        "output": str(tmp_path / output),
    }
    if images is not None:
        doc["images"] = images
    path = tmp_path / f"{output}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def rows_by_key(folder: Path) -> dict[str, dict]:
    return {
        r.key: {
            "raw": r.raw_response,
            "requests": [e.request_hash for e in r.exchanges],
            "images": [e.image_hashes for e in r.exchanges],
            "prediction": r.prediction.model_dump(),
        }
        for r in read_rows(folder / "results.jsonl")
    }


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_run_restarted_with_another_transport_resumes_from_the_cache_with_zero_new_requests(
    tmp_path, mini_root, model_server, api_key
):
    first = run_pipeline(load_pipeline(write_pipeline(tmp_path, mini_root, model_server, output="inline")))
    assert first.summary.rows.answered == N_INSTANCES
    sent = model_server.request_count
    assert sent == N_INSTANCES and all(img.scheme == "data" for r in model_server.requests for img in r.images)

    for transport, images in [
        ("file", {"transport": "file"}),
        ("http", {"transport": "http", "bind": f"127.0.0.1:{free_port()}"}),
    ]:
        again = run_pipeline(load_pipeline(write_pipeline(tmp_path, mini_root, model_server, output=transport, images=images)))
        assert model_server.request_count == sent, transport  # every answer came from the cache
        assert again.stats.cache_hits == N_INSTANCES
        assert rows_by_key(tmp_path / transport) == rows_by_key(tmp_path / "inline")


def test_the_same_folder_resumes_under_another_transport(tmp_path, mini_root, model_server, api_key):
    config = write_pipeline(tmp_path, mini_root, model_server, output="run")
    run_pipeline(load_pipeline(config, overrides={"instances": {"limit": 6}}))
    assert model_server.request_count == 6
    # the rest of the run by reference: the folder is the same pipeline (transport is not part of it)
    result = run_pipeline(load_pipeline(config, overrides={"images": {"transport": "file"}}))
    assert result.n_pending == N_INSTANCES - 6
    assert model_server.request_count == N_INSTANCES
    later = model_server.requests[6:]
    assert later and all(img.scheme == "file" for r in later for img in r.images)
    assert len(rows_by_key(tmp_path / "run")) == N_INSTANCES


def test_every_frame_sent_by_reference_arrives_intact(tmp_path, mini_root, model_server, api_key):
    run_pipeline(load_pipeline(write_pipeline(tmp_path, mini_root, model_server, output="run", images={"transport": "file"})))
    fetched = [img for r in model_server.requests for img in r.images]
    assert fetched and all(img.scheme == "file" for img in fetched)
    assert all(hashlib.sha256(img.data).hexdigest() == img.sha256 for img in fetched)
    sent_hashes = [h for row in read_rows(tmp_path / "run" / "results.jsonl") for e in row.exchanges for h in e.image_hashes]
    assert sorted(img.sha256 for img in fetched) == sorted(sent_hashes)


def test_o_plot_markers_travel_over_http_from_the_cache_folder(tmp_path, mini_root, model_server, api_key):
    port = free_port()
    config = write_pipeline(tmp_path, mini_root, model_server, output="run", strategy="o-plot",
                            images={"transport": "http", "bind": f"127.0.0.1:{port}"})
    result = run_pipeline(load_pipeline(config))
    assert result.summary.rows.answered == N_INSTANCES
    cached = {p.stem for p in (tmp_path / "run" / "image-cache").glob("*.png")}
    fetched = {img.sha256 for r in model_server.requests for img in r.images}
    assert cached and cached <= fetched  # marked frames were written once and fetched by URL
    assert all(url.startswith(f"http://127.0.0.1:{port}/") for r in model_server.requests for url in r.image_urls())
    with pytest.raises(OSError):  # the static server stopped with the run
        socket.create_connection(("127.0.0.1", port), timeout=1)


def test_a_hosted_provider_is_refused_references_before_the_run_folder_is_touched(tmp_path, mini_root, model_server, api_key):
    config = write_pipeline(tmp_path, mini_root, model_server, output="run", model="gemini/gemini-2.5-flash",
                            images={"transport": "file"})
    doc = yaml.safe_load(config.read_text())
    del doc["backend"]["options"]["api_base"]
    config.write_text(yaml.safe_dump(doc))
    with pytest.raises(ConfigError, match="transport file"):
        run_pipeline(load_pipeline(config))
    assert not (tmp_path / "run").exists()
    assert model_server.request_count == 0


def test_a_sweep_refuses_references_for_a_hosted_cell_before_any_cell_runs(tmp_path, mini_root, api_key):
    from povagent.run.sweep import run_sweep

    sweep = {
        "base": {"dataset": str(mini_root), "backend": "center", "images": {"transport": "file"}, "cache": False},
        "output": str(tmp_path / "sweep"),
        "axes": {"backend": ["center", {"name": "litellm", "options": {"model": "gemini/gemini-2.5-flash"}}]},
    }
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(sweep, sort_keys=False))
    with pytest.raises(ConfigError, match=r"gemini/gemini-2.5-flash"):
        run_sweep(path, quiet=True)
    assert not list((tmp_path / "sweep").glob("*/results.jsonl"))  # not even the center cell ran

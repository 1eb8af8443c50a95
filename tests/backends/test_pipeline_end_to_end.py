"""Backends through the whole pipeline (config -> runner -> parser -> scorer -> rows).

A sweep over center, random, oracle and a litellm model served by a loopback server runs end
to end on the hand-made dataset; the oracle's error is ~0; transient faults injected at the
server are retried by the runner and answered, while 400 and 401 are recorded as infra errors
without a retry; the Router over two servers carries a whole run.
"""

from __future__ import annotations

import base64
import json
import time
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.run.sweep import run_sweep
from povagent.testing.loopback_server import Fault, LoopbackServer, RecordedRequest, Reply

pytestmark = pytest.mark.timeout(90)

N_INSTANCES = 18  # the fixture's two good houses


AB_ANSWER = 'Looking at the frames... {"selected_image": 1, "x": 300, "y": 280}'
C_ANSWER = '{"x": 200, "y": 310}'


def answer_for(request: RecordedRequest) -> str:
    """A plausible model answer in the asked format (A/B show several images, C one)."""
    images = [p for p in request.user_parts() if p.get("type") == "image_url"]
    return AB_ANSWER if len(images) > 1 else C_ANSWER


@pytest.fixture
def model_server():
    with LoopbackServer(reply=answer_for, max_lifetime_s=80) as server:
        yield server


def litellm_backend(*servers: LoopbackServer, **options) -> dict:
    if len(servers) == 1:
        opts = {"model": "openai/loopback-vlm", "api_base": servers[0].url, "api_key_env": "POVAGENT_TEST_KEY"}
    else:
        opts = {
            "model": "loopback-vlm",
            "router": [
                {"litellm_params": {"model": "openai/loopback-vlm", "api_base": s.url, "api_key_env": "POVAGENT_TEST_KEY"}}
                for s in servers
            ],
        }
    return {"name": "litellm", "options": {**opts, **options}}


def write_yaml(path: Path, doc: dict) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def pipeline(tmp_path: Path, mini_root: Path, backend, **extra) -> dict:
    return {
        "dataset": str(mini_root),
        "backend": backend,
        "strategy": "basic",
        "parser": "json",
        "concurrency": 4,
        "retry": {"attempts": 3, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 20,
        "cache": False,
        "output": str(tmp_path / "run"),
        **extra,
    }


def run_yaml(tmp_path: Path, doc: dict):
    return run_pipeline(load_pipeline(write_yaml(tmp_path / "pipeline.yaml", doc)))


# -- the sweep -----------------------------------------------------------------------------------
def test_sweep_over_baselines_and_a_served_model_runs_end_to_end(tmp_path, mini_root, model_server, api_key):
    base = pipeline(tmp_path, mini_root, "center", cache=True)
    del base["output"]
    sweep = {
        "base": base,
        "output": str(tmp_path / "sweep"),
        "axes": {"backend": ["center", "random", "oracle", litellm_backend(model_server)]},
    }
    result = run_sweep(write_yaml(tmp_path / "sweep.yaml", sweep), quiet=True)
    summaries = {name: r.summary for name, r in result.results.items()}
    assert len(summaries) == 4
    for name, summary in summaries.items():
        assert summary.complete, name
        assert summary.rows.answered == N_INSTANCES, name
    by_backend = {s.pipeline.backend: s.overall.mean_l2 for s in summaries.values()}
    assert by_backend["oracle"] < 1e-3
    assert by_backend["oracle"] < min(by_backend["center"], by_backend["random"], by_backend["litellm"])
    assert model_server.request_count == N_INSTANCES
    index = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert index  # the sweep index is written


def test_served_model_rows_record_raw_answers_tokens_and_prediction(tmp_path, mini_root, model_server, api_key):
    run_yaml(tmp_path, pipeline(tmp_path, mini_root, litellm_backend(model_server)))
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    ab = [r for r in rows if r.condition in ("a", "b")]
    c = [r for r in rows if r.condition == "c"]
    assert ab and all(r.raw_response == AB_ANSWER for r in ab)
    assert c and all(r.raw_response == C_ANSWER for r in c)
    assert all(r.prediction.selected_image == 1 and (r.prediction.x, r.prediction.y) == (300, 280) for r in ab)
    assert all(r.prompt_tokens == 10 and r.completion_tokens == 5 for r in rows)


def test_oracle_error_is_zero_through_the_runner(tmp_path, mini_root):
    result = run_yaml(tmp_path, pipeline(tmp_path, mini_root, "oracle"))
    assert result.summary.overall.response_rate == 1.0
    assert result.summary.overall.mean_l2 < 1e-3


# -- faults through the runner -------------------------------------------------------------------
def test_transient_faults_are_retried_by_the_runner_and_answered(tmp_path, mini_root, model_server, api_key):
    # concurrency 1: the script is consumed in order, two faults per key for the first keys
    model_server.script(
        Fault(429, retry_after=0), Fault(500), answer_for,  # key 1: rate limit, server error, answer
        Fault(drop=True), Reply("late", delay_s=10),  # key 2: dropped connection, timeout, answer
    )
    doc = pipeline(tmp_path, mini_root, litellm_backend(model_server, timeout=0.5), concurrency=1)
    result = run_yaml(tmp_path, doc)
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    assert result.summary.rows.answered == N_INSTANCES
    assert sum(r.retries for r in rows) == 4
    assert model_server.request_count == N_INSTANCES + 4


def test_a_bad_request_is_recorded_per_key_and_not_retried(tmp_path, mini_root, model_server, api_key):
    model_server.reply = Fault(400, message="injected 400")
    doc = pipeline(tmp_path, mini_root, litellm_backend(model_server), instances={"limit": 3})
    result = run_yaml(tmp_path, doc)
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    assert len(rows) == 3  # a 400 may be one instance's fault (its images, its length): the run goes on
    assert all(r.status == "infra_error" and r.error_type == "bad_request" and r.retries == 0 for r in rows)
    assert all("injected 400" in (r.error_message or "") for r in rows)
    assert model_server.request_count == 3 and result.exit_code == 3


def test_an_auth_failure_stops_the_run_at_the_first_request_naming_model_and_server(tmp_path, mini_root, model_server, api_key):
    model_server.reply = Fault(401, message="injected 401")
    doc = pipeline(tmp_path, mini_root, litellm_backend(model_server), instances={"limit": 3})
    result = run_yaml(tmp_path, doc)
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "infra_error" and row.error_type == "auth" and row.retries == 0
    assert model_server.request_count == 1 and result.exit_code == 4
    assert model_server.url in result.stopped and "auth" in result.stopped


def test_an_unreachable_server_is_a_connection_failure_naming_its_url(tmp_path, mini_root, api_key):
    import socket

    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    url = f"http://127.0.0.1:{port}/v1"
    backend = {"name": "litellm", "options": {"model": "openai/test-model", "api_base": url, "api_key_env": "POVAGENT_TEST_KEY"}}
    doc = pipeline(tmp_path, mini_root, backend, instances={"limit": 3}, retry={"attempts": 2, "initial_wait": 0.0, "max_wait": 0.0})
    result = run_yaml(tmp_path, doc)
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    # refused before the server ever answered: not retried (tests/backends/test_unreachable_at_start.py)
    assert row.error_type == "connection" and url in (row.error_message or "") and row.retries == 0
    assert result.stopped is not None and url in result.stopped and result.exit_code == 4


def test_the_key_never_reaches_rows_or_logs(tmp_path, mini_root, model_server, api_key):
    model_server.reply = Fault(401, message=f"Incorrect API key provided: {api_key}")
    run_yaml(tmp_path, pipeline(tmp_path, mini_root, litellm_backend(model_server), instances={"limit": 2}))
    for name in ("results.jsonl", "log.jsonl", "summary.json", "config.yaml"):
        path = tmp_path / "run" / name
        if path.exists():
            assert api_key not in path.read_text(), name


# -- the Router over two servers -----------------------------------------------------------------
def test_router_over_two_servers_carries_a_whole_run(tmp_path, mini_root, model_server, api_key):
    with LoopbackServer(reply=answer_for, max_lifetime_s=80) as second:
        result = run_yaml(tmp_path, pipeline(tmp_path, mini_root, litellm_backend(model_server, second)))
    assert result.summary.rows.answered == N_INSTANCES
    assert model_server.request_count > 0 and second.request_count > 0
    assert model_server.request_count + second.request_count == N_INSTANCES


# -- what a full pipeline sends --------------------------------------------------------------------
def test_a_full_pipeline_sends_30_labelled_frames_in_order_with_the_prompt_and_parameters(tmp_path, tiny_dataset, model_server, api_key):
    root = tiny_dataset(houses=1, pairs=1, pair_directions=1, frames=30)
    backend = litellm_backend(model_server, temperature=0.2, extra={"top_p": 0.9, "seed": 3})
    run_yaml(tmp_path, pipeline(tmp_path, root, backend, instances={"conditions": ["a"]}))
    assert model_server.request_count == 1
    request = model_server.requests[0]
    parts = request.user_parts()
    assert len(parts) == 2 * 30 + 1
    frames = sorted((root / "artifacts" / "train_house_00000" / "exploration_images").glob("*.png"))
    for i, frame in enumerate(frames):
        assert parts[2 * i] == {"type": "text", "text": f"Image {i}:"}
        url = parts[2 * i + 1]["image_url"]["url"]
        assert url.startswith("data:image/png;base64,")
        assert base64.b64decode(url.split(",", 1)[1]) == frame.read_bytes(), f"image {i} is not frame_{i:03d}"
    prompt = parts[-1]["text"]
    assert "The 30 images above (labeled Image 0 through Image 29)" in prompt
    assert 'Sentence: "While reading, I left the book right of the bed."' in prompt
    assert '{"selected_image": <integer 0-29>, "x": <integer 0-511>, "y": <integer 0-511>}' in prompt
    body = request.body
    assert body["model"] == "loopback-vlm"
    assert (body["max_tokens"], body["temperature"], body["top_p"], body["seed"]) == (256, 0.2, 0.9, 3)


def test_the_runner_waits_for_the_servers_retry_after(tmp_path, mini_root, model_server, api_key):
    model_server.script(Fault(429, retry_after=1))
    run_yaml(tmp_path, pipeline(tmp_path, mini_root, litellm_backend(model_server), instances={"limit": 1}))
    first, second = model_server.requests
    assert second.received_at - first.received_at >= 0.95  # the backoff alone would be 0 s here
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "answered" and row.retries == 1


def test_the_key_never_reaches_any_file_of_the_run_or_its_cache(tmp_path, mini_root, model_server, api_key):
    model_server.script(answer_for, answer_for)  # two answers (cached), then refusals quoting the key
    model_server.reply = Fault(401, message=f"Incorrect API key provided: {api_key}")
    run_yaml(tmp_path, pipeline(tmp_path, mini_root, litellm_backend(model_server), cache=True, instances={"limit": 4}))
    files = [p for p in (tmp_path / "run").rglob("*") if p.is_file()]
    assert any(p.name.startswith("cache") for p in files)
    for path in files:
        assert api_key.encode() not in path.read_bytes(), path.name


# -- model profiles through the runner -------------------------------------------------------------
def test_a_profile_named_in_the_backend_options_brings_its_parser(tmp_path, mini_root):
    # qwen3-vl-32b answers on 0-1000: its profile's official parser keeps the answer as the
    # paper scores it (out of range, clamped by the scorer); rescale-1000 is the opt-in repair
    with LoopbackServer(reply='{"selected_image": 1, "x": 900, "y": 800}', max_lifetime_s=60) as server:
        backend = {"name": "litellm", "options": {"model": "qwen3-vl-32b", "api_base": server.url}}
        doc = pipeline(tmp_path, mini_root, backend, instances={"conditions": ["a"], "limit": 1})
        del doc["parser"]  # the profile's default
        result = run_yaml(tmp_path, doc)
        assert server.requests[0].body["model"] == "Qwen/Qwen3-VL-32B-Instruct"  # hosted_vllm/ prefix stripped
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.parser == "official" and row.status == "answered"
    assert (row.prediction.x, row.prediction.y) == (900, 800)
    assert result.summary.pipeline.parser == "official"


def test_a_given_only_profile_refuses_frames_without_calling_the_model(tmp_path, mini_root):
    with LoopbackServer(reply='[(0.5, 0.5)]', max_lifetime_s=60) as server:
        backend = {"name": "litellm", "options": {"model": "robopoint", "api_base": server.url}}
        doc = pipeline(tmp_path, mini_root, backend, instances={"conditions": ["a", "c"], "directions": ["right"]})
        del doc["parser"]  # the profile's default: robopoint-official
        run_yaml(tmp_path, doc)
        calls = server.request_count
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    a_rows = [r for r in rows if r.condition == "a"]
    c_rows = [r for r in rows if r.condition == "c"]
    assert a_rows and all(r.status == "infra_error" and "Given (c) only" in r.error_message for r in a_rows)
    assert c_rows and all(r.status == "answered" for r in c_rows)
    assert calls == len(c_rows)


# -- the Router and the runner's retries never stack ------------------------------------------------
def test_a_router_failure_is_final_the_runner_does_not_retry_it(tmp_path, mini_root, model_server, api_key):
    with LoopbackServer(reply=Fault(500), max_lifetime_s=80) as second:
        model_server.reply = Fault(500)
        backend = litellm_backend(model_server, second, router_settings={"num_retries": 1, "retry_after": 0})
        run_yaml(tmp_path, pipeline(tmp_path, mini_root, backend, instances={"limit": 2}))
        calls = model_server.request_count + second.request_count
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    assert all(r.status == "infra_error" and r.retries == 0 for r in rows)
    assert calls == 2 * 2  # per key: the Router's first attempt and its one retry; no runner retry on top


def test_a_runner_timeout_on_a_router_is_final_too(tmp_path, mini_root, model_server, api_key):
    with LoopbackServer(reply=Reply("late", delay_s=10), max_lifetime_s=80) as second:
        model_server.reply = Reply("late", delay_s=10)
        backend = litellm_backend(model_server, second, router_settings={"num_retries": 0})
        started = time.monotonic()
        run_yaml(tmp_path, pipeline(tmp_path, mini_root, backend, timeout=0.5, instances={"limit": 1}))
        assert time.monotonic() - started < 8
        calls = model_server.request_count + second.request_count
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "infra_error" and row.error_type == "timeout" and row.retries == 0
    assert calls == 1


# -- replay -------------------------------------------------------------------------------------------
def test_replaying_a_run_or_its_official_export_reproduces_its_predictions(tmp_path, mini_root):
    from povagent.report.export import export_run

    first = run_yaml(tmp_path, pipeline(tmp_path, mini_root, {"name": "random", "options": {"seed": 5}}))
    original = {r.key: r for r in read_rows(tmp_path / "run" / "results.jsonl")}
    (official,) = export_run(tmp_path / "run", tmp_path / "official.json")
    for name, path in (("from_run", tmp_path / "run"), ("from_official", official)):
        doc = pipeline(tmp_path, mini_root, {"name": "replay", "options": {"path": str(path)}}, output=str(tmp_path / name))
        write_yaml(tmp_path / f"{name}.yaml", doc)
        result = run_pipeline(load_pipeline(tmp_path / f"{name}.yaml"))
        replayed = {r.key: r for r in read_rows(tmp_path / name / "results.jsonl")}
        assert replayed.keys() == original.keys(), name
        for key, row in replayed.items():
            assert row.prediction == original[key].prediction, (name, key)
        assert result.summary.overall.mean_l2 == pytest.approx(first.summary.overall.mean_l2), name

"""The built-in tools are registered like any plugin's, and nothing a model is sent changed by it:
the tools' schemas, the preamble, every request of a fixed episode (its hash, as rows name it)
and the config hash are pinned to the bytes the active mode sent before tools were registered,
so results and run folders made before compare and resume."""

from __future__ import annotations

import hashlib
import json

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, Reply
from povagent_plugins.strategies.active import preamble

pytestmark = pytest.mark.timeout(120)

#: SHA-256 of the ``tools`` list every request sent (JSON as the server received it).
TOOLS_SHA = "257f62899100ef4dfb553c612d0f96277d80eb84049a1533677ce4b6ce176ec2"
#: SHA-256 of the preamble for (8 actions, 8 frames, A/B) and for (3 actions, 1 frame, Given).
PREAMBLE_SHA = {
    (8, 8, False): "304746aeb422a86345fa2d0af14edfc191e0da21feef4e892dade4443122ff02",
    (3, 1, True): "6213255398621c5addeb4e329970c8f2477f9f8a43df9884ca074611f4901205",
}
#: The request hashes of the fixed episode's rows, and the pipeline's config hash. The frames
#: they carry are the same bytes under every embree ISA and numpy dispatch level
#: (``tests/generate/test_bytes_across_cpus.py`` holds that for a set of its own).
REQUEST_HASHES = [
    "21b6716448b41ad68e90467bd3e15ab383940402c772378ea16ecbe890ec67e0",
    "8a9279bb399fac3872d482191b65a3c92a1e4c97ce3f1fa16e8e7918f48136a4",
    "57b566f3d972f2bb271317d079227d4e2306f976263047935f60adcffe4714fc",
    "57b566f3d972f2bb271317d079227d4e2306f976263047935f60adcffe4714fc",
]
CONFIG_HASH = "297bdeca86bcd130"


def sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def calls(*pairs: tuple[str, object]) -> Reply:
    return Reply(None, tool_calls=tuple({"name": n, "arguments": a} for n, a in pairs))


@pytest.fixture(scope="module")
def episode_run(generated_release, tmp_path_factory):
    """A fixed episode over HTTP: every tool once, then the answer; (server, row, config). Run
    once a module: its tests only read the requests, the row and the hashes."""
    tmp_path = tmp_path_factory.mktemp("tool-bytes")
    with pytest.MonkeyPatch.context() as monkeypatch, LoopbackServer(reply="I cannot tell.", max_lifetime_s=100) as server:
        monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-not-a-key")
        server.script(calls(("go_to_frame", {"frame": 1}), ("turn", {"degrees": 10}), ("tilt", {"degrees": -5})),
                      calls(("move", {"forward": 0.5, "right": 0.0}), ("ask", {"question": "What were you doing?"})),
                      calls(("answer", {"image": "view 2", "x": 100, "y": 200})))  # fmt: skip
        doc = {
            "dataset": {"path": str(generated_release)},
            "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
            "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": "http://127.0.0.1:9/v1",
                                                       "api_key_env": "POVAGENT_TEST_KEY"}},
            "strategy": {"name": "active", "options": {"max_actions": 6}},
            "parser": "active",
            "scorers": ["official"],
            "retry": {"attempts": 1},
            "output": str(tmp_path / "run"),
        }  # fmt: skip
        path = tmp_path / "pipeline.yaml"
        path.write_text(yaml.safe_dump(doc))
        config = load_pipeline(path)
        # the server's port changes each run: the pinned hash is of the config naming a fixed one
        pinned_hash = config.config_hash()
        doc["backend"]["options"]["api_base"] = server.url
        path.write_text(yaml.safe_dump(doc))
        config = load_pipeline(path)
        run_pipeline(config)
        (row,) = read_rows(tmp_path / "run" / "results.jsonl")
        yield server, row, (pinned_hash, config.config_hash())


def test_every_request_offers_the_built_in_tools_in_their_exact_bytes(episode_run):
    server, _, _ = episode_run
    sent = [json.dumps(r.body["tools"], sort_keys=True, separators=(",", ":")) for r in server.requests]
    assert len(sent) == 3 and {sha(s) for s in sent} == {TOOLS_SHA}


def test_the_preamble_keeps_its_exact_text():
    assert {args: sha(preamble(*args)) for args in PREAMBLE_SHA} == PREAMBLE_SHA


def test_every_request_of_a_fixed_episode_keeps_its_hash(episode_run):
    _, row, _ = episode_run
    assert row.status == "answered"
    assert [e.request_hash for e in row.exchanges] == REQUEST_HASHES


def test_the_config_hash_of_a_pipeline_offering_the_built_in_tools_is_unchanged(episode_run):
    _, row, (pinned_hash, plain_hash) = episode_run
    assert pinned_hash == CONFIG_HASH
    assert row.config_hash == plain_hash  # the run's rows carry the config's own hash: nothing added

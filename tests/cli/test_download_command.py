"""``povagent download``: run as a user runs it, in a fresh process whose environment names the Hub.

huggingface_hub reads ``HF_ENDPOINT``, ``HF_HOME`` and ``HF_HUB_OFFLINE`` when it is imported, so
each command runs in a subprocess started with them set: the path a user's shell takes.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from povagent.testing.hub_server import HubServer


@pytest.fixture
def hub(mini_root):
    with HubServer(mini_root, max_lifetime_s=120) as server:
        yield server


def povagent(args: list[str], hf_home: Path, endpoint: str, offline: bool = False) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("HF_", "HUGGINGFACE_", "TRANSFORMERS_"))}
    env |= {"HF_HOME": str(hf_home), "HF_ENDPOINT": endpoint, "HF_HUB_DISABLE_TELEMETRY": "1"}
    if offline:
        env["HF_HUB_OFFLINE"] = "1"
    return subprocess.run(
        [sys.executable, "-m", "povagent.cli", "download", *args],
        env=env, capture_output=True, text=True, timeout=90,
    )  # fmt: skip


def test_download_prints_the_release_root_in_the_hf_cache(hub, tmp_path):
    done = povagent(["owl-owl/POVBench"], tmp_path / "hf", hub.url)
    assert done.returncode == 0, done.stderr
    root = Path(done.stdout.strip().splitlines()[-1])
    assert root == tmp_path / "hf" / "hub" / "datasets--owl-owl--POVBench" / "snapshots" / hub.commit
    assert (root / "artifacts").is_dir() and f"commit {hub.commit[:12]}" in done.stdout
    assert "Fetching" in done.stderr  # huggingface_hub's progress bar


def test_download_of_given_only_then_offline(hub, tmp_path):
    done = povagent(["owl-owl/POVBench", "--conditions", "c", "--quiet"], tmp_path / "hf", hub.url)
    assert done.returncode == 0, done.stderr
    assert not any("exploration_images" in f for f in hub.fetched_files())
    hub.stop()
    again = povagent(["--conditions", "given", "-q"], tmp_path / "hf", hub.url, offline=True)
    assert again.returncode == 0, again.stderr
    assert again.stdout.strip().splitlines()[-1] == done.stdout.strip().splitlines()[-1]
    # the frames were never fetched: an Inferred run cannot be served from this cache
    needs_frames = povagent(["--conditions", "a", "-q"], tmp_path / "hf", hub.url, offline=True)
    assert needs_frames.returncode == 2 and "owl-owl/POVBench @ main" in needs_frames.stderr
    assert "Traceback" not in needs_frames.stderr


def test_a_missing_revision_is_a_clear_error(hub, tmp_path):
    done = povagent(["--revision", "v404", "-q"], tmp_path / "hf", hub.url)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "error: owl-owl/POVBench @ v404: the revision does not exist" in done.stderr


def test_no_network_is_a_clear_error(hub, tmp_path):
    hub.stop()
    done = povagent(["-q"], tmp_path / "hf", hub.url)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "error: owl-owl/POVBench @ main: cannot reach the Hub at " + hub.url in done.stderr

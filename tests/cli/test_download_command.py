"""``povagent download``, with its environment naming the Hub.

huggingface_hub reads ``HF_ENDPOINT``, ``HF_HOME`` and ``HF_HUB_OFFLINE`` when it is imported;
povagent reads them at each call. The first download runs as a user runs it, in a fresh
process started with them set (the path a user's shell takes, progress bar included); the
others run in this process with them set for the call (the ``console_here`` fixture, which
shows an error as the console script does).
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


def povagent(args: list[str], hf_home: Path, endpoint: str, offline: bool = False, here=None):
    """``povagent download ARGS``: in a fresh process, or through ``here`` (``console_here``)."""
    others = [k for k in os.environ if k.startswith(("HF_", "HUGGINGFACE_", "TRANSFORMERS_"))]
    hf = {"HF_HOME": str(hf_home), "HF_ENDPOINT": endpoint, "HF_HUB_DISABLE_TELEMETRY": "1"}
    if offline:
        hf["HF_HUB_OFFLINE"] = "1"
    if here is not None:
        return here(["download", *args], env=dict.fromkeys(others) | hf)
    env = {k: v for k, v in os.environ.items() if k not in others} | hf
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


def test_download_of_given_only_then_offline(hub, tmp_path, console_here):
    done = povagent(["owl-owl/POVBench", "--conditions", "c", "--quiet"], tmp_path / "hf", hub.url, here=console_here)
    assert done.returncode == 0, done.stderr
    assert not any("exploration_images" in f for f in hub.fetched_files())
    hub.stop()
    again = povagent(["--conditions", "given", "-q"], tmp_path / "hf", hub.url, offline=True, here=console_here)
    assert again.returncode == 0, again.stderr
    assert again.stdout.strip().splitlines()[-1] == done.stdout.strip().splitlines()[-1]
    # the frames were never fetched: an Inferred run cannot be served from this cache
    needs_frames = povagent(["--conditions", "a", "-q"], tmp_path / "hf", hub.url, offline=True, here=console_here)
    assert needs_frames.returncode == 2 and "owl-owl/POVBench @ main" in needs_frames.stderr
    assert "Traceback" not in needs_frames.stderr


def test_a_missing_revision_is_a_clear_error(hub, tmp_path, console_here):
    done = povagent(["--revision", "v404", "-q"], tmp_path / "hf", hub.url, here=console_here)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "error: owl-owl/POVBench @ v404: the revision does not exist" in done.stderr


def test_no_network_is_a_clear_error(hub, tmp_path, console_here):
    hub.stop()
    done = povagent(["-q"], tmp_path / "hf", hub.url, here=console_here)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "error: owl-owl/POVBench @ main: cannot reach the Hub at " + hub.url in done.stderr

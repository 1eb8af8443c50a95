"""SIGTERM (what schedulers and ``timeout`` send) stops ``run`` and ``sweep`` as cleanly as Ctrl-C:
rows kept, the summary marked interrupted, a message saying how to resume, exit code 143; the
same command then finishes with every key exactly once. Real signals, a real slow model server
on loopback."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest
import yaml
from command_forks import Command

from povagent.config.pipeline import load_pipeline
from povagent.run.progress import QuietProgress
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, Reply

pytestmark = pytest.mark.timeout(240)

N_KEYS = 18  # the 6 Given instances of the dataset copy's two houses, 3 runs
ANSWER = '{"selected_image": 0, "x": 256, "y": 256}'


@pytest.fixture
def slow_server():
    with LoopbackServer(Reply(ANSWER, delay_s=0.15), max_lifetime_s=220) as server:
        yield server


def pipeline(tmp_path: Path, dataset: Path, server: LoopbackServer, output: Path, **keys: object) -> Path:
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": str(dataset),
        "instances": {"conditions": ["c"]},  # one frame a request: light on a loaded machine
        "runs": 3,
        "backend": {"name": "litellm", "options": {"model": "openai/loopback", "api_base": server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
        "parser": "official",
        "concurrency": 3,
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "cache": False,
        "output": str(output),
        **keys,
    }))
    return path


def keys(results: Path) -> list[str]:
    return [json.loads(line)["key"] for line in results.read_text().splitlines()]


def start(forks, *args: str, cwd: Path) -> Command:
    """``povagent ARGS --quiet`` started in a process of its own (tests/run/command_forks.py)."""
    env = {**os.environ, "POVAGENT_TEST_KEY": "sk-test-123", "PYTHONUNBUFFERED": "1"}
    return forks.start(*args, "--quiet", cwd=cwd, env=env)


def terminate_after_rows(proc: Command, results: Path, rows: int) -> tuple[str, str]:
    """SIGTERM once ``results`` holds ``rows`` lines; the process's (stdout, stderr)."""
    deadline = time.monotonic() + 120
    while not results.exists() or len(results.read_text().splitlines()) < rows:
        assert proc.poll() is None, (proc.stdout(), proc.stderr())
        assert time.monotonic() < deadline, "no rows in time"
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=60)
    return proc.stdout(), proc.stderr()


def test_sigterm_mid_run_stops_cleanly_and_the_same_command_resumes(tmp_path, dataset_copy, slow_server, monkeypatch, command_forks):
    run = tmp_path / "run"
    path = pipeline(tmp_path, dataset_copy, slow_server, run)
    proc = start(command_forks, "run", str(path), cwd=tmp_path)
    _, err = terminate_after_rows(proc, run / "results.jsonl", 3)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    assert f"terminated (SIGTERM): rows written so far are kept in {run}" in err and f"povagent run {path}` again to resume" in err, err
    summary = json.loads((run / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["complete"] is False
    before = keys(run / "results.jsonl")
    assert 3 <= len(before) < N_KEYS, "the signal must land mid-run"
    assert summary["rows"]["done"] == len(before)

    # the resume is the same pipeline run in this process: what the signal left is resumed as
    # the command resumes it (a second interpreter importing litellm costs 3-4 s of CPU, and how
    # the command ends a finished run is the sweep test's below and tests/cli/test_process_exit.py's)
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-123")
    resumed = run_pipeline(load_pipeline(path), progress=QuietProgress())
    assert resumed.exit_code == 0 and resumed.n_pending == N_KEYS - len(before), (resumed.exit_code, resumed.n_pending)
    after = keys(run / "results.jsonl")
    assert len(after) == len(set(after)) == N_KEYS and after[: len(before)] == before
    assert json.loads((run / "summary.json").read_text())["interrupted"] is False


def test_sigterm_mid_sweep_stops_cleanly_and_the_same_command_resumes(tmp_path, dataset_copy, offline_plugin_file, command_forks):
    # one request at a time: the cell's last rows are a few tenths of a second away when the
    # signal is sent, so a test process slowed by load still signals mid-cell (the moment the
    # cell finishes is aimed at on purpose in test_stop_window.py). The model is the offline
    # test backend, as slow as the server above: a request cut by the signal is the run test's
    # (two sweep processes that import litellm cost 7 s of CPU and test nothing more here)
    (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": [str(offline_plugin_file)],
        "dataset": str(dataset_copy),
        "instances": {"conditions": ["c"]},
        "runs": 1,
        "backend": {"name": "test-center", "options": {"delay_s": 0.15, "reply": ANSWER}},
        "parser": "official",
        "concurrency": 1,
        "cache": False,
        "output": str(tmp_path / "ignored"),
    }))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sw"), "axes": {"parser": ["official", "json"]}}))
    proc = start(command_forks, "sweep", str(sweep), cwd=tmp_path)
    _, err = terminate_after_rows(proc, tmp_path / "sw" / "official" / "results.jsonl", 2)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and f"terminated (SIGTERM): finished rows are kept; run `povagent sweep {sweep}` again" in err, err
    official = tmp_path / "sw" / "official"
    assert (official / "summary.json").exists(), (err, sorted(p.name for p in official.iterdir()), keys(official / "results.jsonl"))
    assert json.loads((official / "summary.json").read_text())["interrupted"] is True
    before = keys(tmp_path / "sw" / "official" / "results.jsonl")
    assert len(before) < N_KEYS // 3  # a cell runs once: 6 keys

    proc = start(command_forks, "sweep", str(sweep), cwd=tmp_path)
    assert proc.wait(timeout=180) == 0, proc.stderr()
    for cell in ("official", "json"):
        done = keys(tmp_path / "sw" / cell / "results.jsonl")
        assert len(done) == len(set(done)) == N_KEYS // 3, cell

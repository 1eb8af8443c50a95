"""A checkpoint's own code runs only when the command line grants it: proved with a real tiny
checkpoint whose ``config.json`` ``auto_map`` names a Python file that leaves a marker file when
imported. And a load that never ends (that code sleeping) is still stopped by SIGTERM."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import ConfigError
from povagent.testing.tiny_checkpoints import add_code_leaving_a_marker

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def marked(tmp_path, tiny_idefics3) -> tuple[Path, Path]:
    """A copy of the Idefics3 checkpoint naming code of its own, and where that code leaves its
    marker. The folder's name is the test's own: transformers imports a folder's code once per
    process under the folder's name."""
    folder = tmp_path / f"ckpt_{tmp_path.name}"
    shutil.copytree(tiny_idefics3, folder)
    marker = tmp_path / "marker"
    add_code_leaving_a_marker(folder, marker)
    return folder, marker


def pipeline(tmp_path: Path, mini_root: Path, options: dict) -> Path:
    path = tmp_path / "run.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": str(mini_root),
        "backend": {"name": "transformers", "options": options},
        "strategy": {"name": "basic", "options": {"max_tokens": 4}},
        "instances": {"conditions": ["c"], "houses": ["train_house_00000"], "directions": ["left"]},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 60,
        "output": str(tmp_path / "out"),
    }))
    return path


def test_a_yaml_asking_for_the_checkpoints_code_is_refused_and_the_code_never_runs(tmp_path, mini_root, marked):
    folder, marker = marked
    result = CliRunner().invoke(app, ["run", str(pipeline(tmp_path, mini_root, {"model": str(folder), "trust_remote_code": True}))])
    assert isinstance(result.exception, ConfigError) and "--trust-remote-code" in str(result.exception)
    assert not marker.exists() and not (tmp_path / "out").exists()


def test_without_the_flag_the_checkpoint_loads_its_built_in_class_and_its_code_never_runs(tmp_path, mini_root, marked):
    folder, marker = marked
    result = CliRunner().invoke(app, ["run", str(pipeline(tmp_path, mini_root, {"model": str(folder)})), "--quiet"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out" / "results.jsonl").read_text().count("\n") == 1
    assert not marker.exists()


def test_the_flag_on_the_command_line_runs_the_checkpoints_code(tmp_path, mini_root, marked):
    folder, marker = marked
    CliRunner().invoke(app, ["run", str(pipeline(tmp_path, mini_root, {"model": str(folder)})), "--quiet", "--trust-remote-code"])
    assert marker.read_text() == "the checkpoint's code ran"  # the proof above would see it


def test_sigterm_ends_a_run_whose_checkpoint_load_never_ends_within_15_s(tmp_path, mini_root, tiny_idefics3):
    folder = tmp_path / "hanging"
    shutil.copytree(tiny_idefics3, folder)
    marker = tmp_path / "loading"
    add_code_leaving_a_marker(folder, marker, hang=True)
    path = pipeline(tmp_path, mini_root, {"model": str(folder)})
    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.cli", "run", str(path), "--quiet", "--trust-remote-code"],
        cwd=tmp_path, env={**os.environ, "PYTHONUNBUFFERED": "1"}, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 90
        while not marker.exists():  # the checkpoint's code is running: the load is stuck in it
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the load never started"
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGTERM)
        sent = time.monotonic()
        _, err = proc.communicate(timeout=30)
        assert time.monotonic() - sent < 15, "SIGTERM took longer than 15 s to end the run"
        assert proc.returncode == 143, err
        assert "Traceback" not in err and "terminated (SIGTERM)" in err and "--trust-remote-code` again to resume" in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()

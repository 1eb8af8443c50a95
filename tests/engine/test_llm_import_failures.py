"""An import of litellm that hangs, fails late or finds nothing ends a run with one line, and a
signal ends it at any point of start-up (povagent/engine/llm_import.py).

Each case runs ``povagent run`` in a fresh interpreter with a stand-in ``litellm`` module first
on ``PYTHONPATH``: one that never finishes importing, one that fails after a pause (and counts
its attempts in a file), one that is not there.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(120)

CLI = "from povagent.cli import main; main()"

HANGING = "import time\nwhile True:\n    time.sleep(0.1)\n"
MISSING = "raise ModuleNotFoundError(\"No module named 'litellm'\", name='litellm')\n"


def failing_late(counter: Path, pause_s: float) -> str:
    return (
        "import time\n"
        f"with open({str(counter)!r}, 'a') as f:\n    f.write('attempt\\n')\n"
        f"time.sleep({pause_s})\n"
        "raise ImportError('simulated broken litellm')\n"
    )


def stand_in(tmp_path: Path, source: str) -> Path:
    folder = tmp_path / "stand-in"
    folder.mkdir()
    (folder / "litellm.py").write_text(source)
    return folder


def pipeline(tmp_path: Path, mini_root: Path) -> Path:
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-model", "api_base": "http://127.0.0.1:9/v1",
                                                   "api_key_env": "POVAGENT_TEST_KEY"}},
        "strategy": "basic", "parser": "official", "scorers": ["official"], "output": str(tmp_path / "run"),
    }))  # fmt: skip
    return path


def env_with(folder: Path, **extra: str) -> dict[str, str]:
    env = {**os.environ, "POVAGENT_TEST_KEY": "sk-test", "PYTHONPATH": str(folder), **extra}
    env.pop("POVAGENT_LITELLM_IMPORT_TIMEOUT", None)
    env.update(extra)
    return env


def run(tmp_path: Path, mini_root: Path, folder: Path, **extra: str) -> tuple[subprocess.CompletedProcess[str], float]:
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-c", CLI, "run", str(pipeline(tmp_path, mini_root)), "--quiet"],
                          capture_output=True, text=True, timeout=90, env=env_with(folder, **extra))
    return done, time.monotonic() - t0


def stop_lines(done: subprocess.CompletedProcess[str]) -> list[str]:
    return [line for line in done.stderr.splitlines() if line.startswith("stopped early:")]


def rows(tmp_path: Path) -> list[dict]:
    text = (tmp_path / "run" / "results.jsonl").read_text()
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def _sigint(disposition):
    """A child's SIGINT handling as set before it starts, whatever this process's is (a suite run
    in the background, ``nohup pytest &``, inherits SIGINT ignored)."""
    return lambda: signal.signal(signal.SIGINT, disposition)


@pytest.mark.parametrize(("which", "inherited"), [(signal.SIGTERM, signal.SIG_DFL), (signal.SIGINT, signal.SIG_DFL), (signal.SIGINT, signal.SIG_IGN)],
                         ids=["SIGTERM", "SIGINT", "SIGINT inherited ignored"])  # fmt: skip
def test_a_signal_ends_a_run_whose_litellm_import_never_finishes(tmp_path, mini_root, which, inherited):
    folder = stand_in(tmp_path, HANGING)
    proc = subprocess.Popen([sys.executable, "-c", CLI, "run", str(pipeline(tmp_path, mini_root)), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env_with(folder),
                            preexec_fn=_sigint(inherited))  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / "run" / "results.jsonl").exists() and time.monotonic() < deadline:
            time.sleep(0.1)  # the run folder exists: start-up is past the dataset, waiting for the import
        time.sleep(1.0)
        proc.send_signal(which)
        # generous: on a loaded machine the interpreter's own exit takes seconds; a hang never ends
        _, err = proc.communicate(timeout=45)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == (143 if which == signal.SIGTERM else 130), err[-2000:]
    assert "Traceback" not in err
    assert "rows written so far are kept" in err


def test_an_import_past_its_deadline_is_one_line_at_the_deadline(tmp_path, mini_root):
    folder = stand_in(tmp_path, HANGING)
    done, wall = run(tmp_path, mini_root, folder, POVAGENT_LITELLM_IMPORT_TIMEOUT="2")
    assert done.returncode == 4, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    [line] = stop_lines(done)
    assert "cannot import litellm (TimeoutError: still importing after 2 s)" in line
    assert wall < 30
    assert [r["error_type"] for r in rows(tmp_path)] == ["client_import"]


def test_an_import_that_fails_late_is_waited_for_once(tmp_path, mini_root):
    counter = tmp_path / "attempts.txt"
    folder = stand_in(tmp_path, failing_late(counter, 2.0))
    done, _ = run(tmp_path, mini_root, folder)
    assert done.returncode == 4, done.stderr[-2000:]
    assert counter.read_text().count("attempt") == 1  # the preload's failure is remembered, not repeated
    [line] = stop_lines(done)
    assert "cannot import litellm (ImportError: simulated broken litellm)" in line


def test_a_missing_litellm_is_one_line_and_one_row(tmp_path, mini_root):
    folder = stand_in(tmp_path, MISSING)
    done, _ = run(tmp_path, mini_root, folder)
    assert done.returncode == 4, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    [line] = stop_lines(done)
    assert "cannot import litellm (ModuleNotFoundError: No module named 'litellm')" in line
    assert [r["error_type"] for r in rows(tmp_path)] == ["client_import"]

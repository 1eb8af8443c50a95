"""A served session as the user starts one: a real ``povagent annotate`` process, its URL read
from what it prints, killed by the pid this test started; and an answer-mode YAML."""

from __future__ import annotations

import os
import queue
import subprocess
import sys
import threading
from pathlib import Path

import pytest
import yaml


def write_study(folder: Path, dataset_root: Path, **extra) -> Path:
    """An answer-mode YAML: the basic strategy's prompt, the official scorer, annotator alice."""
    data = {
        "dataset": {"path": str(dataset_root)},
        "backend": "human",
        "annotator": "alice",
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official"],
        "output": str(folder / "human-alice"),
        **extra,
    }
    path = folder / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


class Served:
    """A running ``povagent annotate`` process and the URL it printed."""

    def __init__(self, study: Path) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [sys.executable, "-m", "povagent.cli", "annotate", str(study)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=lambda: [lines.put(line) for line in self.process.stdout], daemon=True).start()  # type: ignore[union-attr]
        # stderr read as it comes too: a full pipe would stop the server mid-answer
        self._said: list[str] = []
        threading.Thread(target=lambda: [self._said.append(line) for line in self.process.stderr], daemon=True).start()  # type: ignore[union-attr]
        self.url = ""
        while not self.url:
            try:
                line = lines.get(timeout=120)
            except queue.Empty:
                self.kill()
                pytest.fail(f"povagent annotate printed no URL: {self.said()}")
            if line.startswith("open "):
                self.url = line.split(" ", 1)[1].strip()

    def wait_all_done(self, page, timeout_ms: float = 120_000) -> None:
        """Wait for the page to say the session is done; a session that never ends fails with
        the page's status and what the server said."""
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        try:
            page.wait_for_function("() => document.getElementById('status').textContent.startsWith('All done')", timeout=timeout_ms)
        except PlaywrightTimeout:
            pytest.fail(f"no 'All done' (page status: {page.locator('#status').text_content()!r}); the server said: {self.said()}")

    def said(self) -> str:
        """The end of what the server wrote on stderr so far (for a failure's message)."""
        return "".join(self._said)[-4000:]

    def kill(self) -> None:
        """SIGKILL, by the pid this test started: no clean shutdown at all."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=60)

    def wait(self) -> int:
        return self.process.wait(timeout=120)

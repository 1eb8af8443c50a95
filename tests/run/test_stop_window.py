"""A SIGTERM that arrives while a sweep cell finishes: between its last row and its summary.

The window behind a flake seen once in CI (exit 143, the first cell's ``summary.json`` missing):
a job started in the background by a script inherits SIGINT ignored, so ``asyncio.run`` never
installs its handler and a SIGTERM used to raise KeyboardInterrupt wherever the code was, here
in the middle of the cell's finalization; with SIGINT's default handler, a SIGTERM arriving while
the journal closed was swallowed and the sweep went on to its next cell. Each test sends a real
SIGTERM to this process at one exact point of that window (from inside the journal's close, an
``await``; or from inside the summary's computation, plain code), in both SIGINT dispositions,
through the real ``sweep`` command in-process with the offline test backend.
"""

from __future__ import annotations

import json
import os
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.run.journal import RowJournal
from povagent.run.runner import PipelineRun

pytestmark = pytest.mark.timeout(120)

KEYS_PER_CELL = 4  # the small release's instances of one condition, one run


@pytest.fixture(params=["SIGINT default", "SIGINT ignored"])
def sigint(request) -> Iterator[str]:
    """SIGINT as an interactive shell leaves it, or ignored as for a job started with ``&``."""
    previous = signal.getsignal(signal.SIGINT)
    if request.param == "SIGINT ignored":
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield request.param
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.fixture
def sweep(tmp_path, write_pipeline) -> Path:
    write_pipeline(output=str(tmp_path / "ignored"))
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sw"), "axes": {"conditions": ["a", "b"]}}))
    return path


def _terminate_once(at: str) -> Callable[[], None]:
    """A function that sends SIGTERM to this process the first time it is called ``at`` a point."""
    sent: list[str] = []

    def send() -> None:
        if sent:
            return
        handler = signal.getsignal(signal.SIGTERM)
        assert callable(handler) and handler is not signal.SIG_DFL, "no SIGTERM handler: the signal would end pytest"
        sent.append(at)
        os.kill(os.getpid(), signal.SIGTERM)

    return send


@pytest.fixture(params=["while the journal closes", "while the summary is computed"])
def window(request, monkeypatch) -> str:
    send = _terminate_once(request.param)
    if request.param == "while the journal closes":
        close = RowJournal.aclose

        async def aclose(self: RowJournal) -> None:
            send()
            await close(self)

        monkeypatch.setattr(RowJournal, "aclose", aclose)
    else:
        summarize = PipelineRun.summarize

        def summarized(self: PipelineRun, *args: Any) -> dict[str, Any]:
            send()
            return summarize(self, *args)

        monkeypatch.setattr(PipelineRun, "summarize", summarized)
    return str(request.param)


def _keys(results: Path) -> list[str]:
    return [json.loads(line)["key"] for line in results.read_text().splitlines()] if results.exists() else []


def test_a_sigterm_while_a_cell_finishes_keeps_its_summary_and_stops_the_sweep(sweep, sigint, window, monkeypatch) -> None:
    result = CliRunner().invoke(app, ["sweep", str(sweep), "--quiet"])
    assert result.exit_code == 143, (sigint, window, result.output, result.exception)
    first, second = sweep.parent / "sw" / "a", sweep.parent / "sw" / "b"
    assert (first / "summary.json").exists(), (sigint, window, sorted(p.name for p in first.iterdir()))
    summary = json.loads((first / "summary.json").read_text())
    assert summary["rows"]["done"] == len(_keys(first / "results.jsonl")) == KEYS_PER_CELL and summary["complete"] is True
    assert summary["interrupted"] is True  # every key done, but the run was stopped before its end
    assert _keys(second / "results.jsonl") == [], "the sweep went on to its next cell after the SIGTERM"
    assert "terminated (SIGTERM): finished rows are kept" in result.output

    monkeypatch.undo()  # the same command again, with nothing in the way
    again = CliRunner().invoke(app, ["sweep", str(sweep), "--quiet"])
    assert again.exit_code == 0, again.output
    for cell in (first, second):
        keys = _keys(cell / "results.jsonl")
        assert len(keys) == len(set(keys)) == KEYS_PER_CELL, cell
        assert json.loads((cell / "summary.json").read_text())["interrupted"] is False

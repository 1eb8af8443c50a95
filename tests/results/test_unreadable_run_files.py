"""A run folder is anyone's once it exists: its results file or its config planted as a named
pipe is one line naming it, at once, for every command that reads the folder; never a wait."""

from __future__ import annotations

import os
import time

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import PovagentError, ReadTargetError
from povagent.results.rows import iter_rows

pytestmark = pytest.mark.timeout(60)


def test_reading_a_results_file_that_is_a_fifo_is_refused_at_once(tmp_path):
    os.mkfifo(tmp_path / "results.jsonl")
    with pytest.raises(ReadTargetError, match=r"results\.jsonl: results file is a named pipe \(FIFO\)"):
        list(iter_rows(tmp_path / "results.jsonl"))


@pytest.mark.parametrize("planted", ["results.jsonl", "config.yaml"])
@pytest.mark.parametrize("command", ["report", "rescore"])
def test_a_command_reading_a_run_folder_names_a_planted_pipe_in_one_line(tmp_path, write_answered_run, command, planted):
    run = write_answered_run(tmp_path / "run", [("train_house_00000/0/left/c", '{"x": 1, "y": 2}')])
    (run / planted).unlink()
    os.mkfifo(run / planted)
    started = time.monotonic()
    result = CliRunner().invoke(app, [command, str(run)])
    assert time.monotonic() - started < 30
    assert isinstance(result.exception, PovagentError), result.output
    message = str(result.exception)
    assert "\n" not in message and planted in message and "named pipe" in message

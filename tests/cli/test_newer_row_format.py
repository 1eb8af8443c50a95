"""A run folder holding a row of a format newer than this povagent is refused by the commands that
read it, with one line naming the file, the line and ``format_version`` (:mod:`povagent.results.upgrade`)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import PredictionsError
from povagent.results.upgrade import ROW_FORMAT

OLD_RUN = Path(__file__).resolve().parents[1] / "fixtures" / "run_before_answer_types"


@pytest.mark.parametrize("command", [["report", "--bootstrap", "0", "--no-gallery"], ["rescore", "--parser", "official"]], ids=["report", "rescore"])
def test_a_row_of_a_newer_format_stops_the_command_in_one_line(tmp_path, command):
    run = tmp_path / "run"
    shutil.copytree(OLD_RUN, run)
    lines = (run / "results.jsonl").read_text(encoding="utf-8").splitlines()
    lines[1] = json.dumps({**json.loads(lines[1]), "format_version": ROW_FORMAT + 1})
    (run / "results.jsonl").write_text("\n".join(lines) + "\n", encoding="utf-8")
    extra = ["--out", str(tmp_path / "report")] if command[0] == "report" else []
    result = CliRunner().invoke(app, [command[0], str(run), *command[1:], *extra])
    assert isinstance(result.exception, PredictionsError), f"not a message: {result.exception!r}"  # main() prints it as one line
    assert str(result.exception) == (
        f"{run / 'results.jsonl'}: line 2: format_version: {ROW_FORMAT + 1} is newer than this povagent reads "
        f"(row formats up to {ROW_FORMAT}); read it with the povagent release that wrote it, or a later one"
    )

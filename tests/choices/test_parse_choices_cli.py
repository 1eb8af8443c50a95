"""``povagent parse --parser NAME --choices ...``: one reply on stdin, the label the rule reads as JSON."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import ConfigError

runner = CliRunner()
OPTIONS = "A=right,B=left,C=front,D=back"


def chosen(reply: str, parser: str, choices: str = OPTIONS):
    """The ``choice`` of the JSON ``povagent parse`` prints."""
    result = runner.invoke(app, ["parse", "--parser", parser, "--choices", choices], input=reply)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)["choice"]


@pytest.mark.parametrize(
    ("parser", "reply", "label"),
    [
        ("viewspatial", "Looking again.\nb", "B"),
        ("mindcube", "A chair blocks the view, so the answer is B.", "B"),
        ("3dsrbench-lmms", "A chair blocks the view, so the answer is B.", "A"),
        ("vlmevalkit-exact", "The lamp is to the left of the sofa.", "B"),
        ("vlmevalkit-spatial", "<answer>d</answer>", "D"),
        ("lmms-mcq-extract", "The answer is C. Because the lamp is ahead.", "B"),
        ("lmms-mcq-extract-corrected", "The answer is C. Because the lamp is ahead.", "C"),
    ],
)
def test_prints_the_label_each_rule_reads(parser, reply, label):
    assert chosen(reply, parser) == label


def test_a_reply_the_rule_reads_no_option_in_prints_null():
    assert chosen("Cannot determine the answer", "vlmevalkit-exact") is None


def test_options_texts_are_what_vlmevalkit_matches_a_reply_against():
    assert chosen("upstairs", "vlmevalkit-exact", "A=downstairs,B=upstairs") == "B"


@pytest.mark.parametrize("bad", ["A=right,B", "A=right,,B=left", "=right", "A=right,A=left", "A="])
def test_a_malformed_choices_list_is_a_clear_error(bad):
    result = runner.invoke(app, ["parse", "--parser", "viewspatial", "--choices", bad], input="B")
    assert isinstance(result.exception, ConfigError) and str(result.exception).startswith("--choices:")


def test_the_console_script_reports_a_malformed_choices_list_in_one_line():
    proc = subprocess.run(
        [sys.executable, "-c", "from povagent.cli import main; main()", "parse", "--parser", "viewspatial", "--choices", "A=right,B"],
        input="B", capture_output=True, text=True, timeout=60,
    )
    assert proc.returncode != 0 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--choices" in lines[0] and "Traceback" not in proc.stderr

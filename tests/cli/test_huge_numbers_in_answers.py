"""A huge number anywhere in a model answer never crashes a command.

``povagent parse`` once crashed on a 400-digit frame index (OverflowError in the reason), and a
report built from an official reading of ``"x": 1e400`` crashed writing its page data. Here a
run folder holding such answers goes through ``parse``, ``rescore`` (official, robopoint,
rescale-1000), ``score``, ``report`` (with its gallery), ``export`` (both formats) and ``compare``.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from povagent.cli import app

pytestmark = pytest.mark.timeout(300)

BIG = "9" * 400
ANSWERS = [
    ("train_house_00000/0/right/a", f'{{"selected_image": {BIG}, "x": 10, "y": 10}}'),
    ("train_house_00000/0/right/b", f'{{"selected_image": 1, "x": {BIG}, "y": -{BIG}}}'),
    ("train_house_00000/0/right/c", f'{{"x": 1e400, "y": {BIG}.5}}'),
    ("train_house_00000/0/left/a", f"Image {BIG}: [({BIG}, 0.5)]"),
    ("train_house_00000/0/left/c", f"[(0.{BIG}, 1e400), (0.5, 0.5)]"),
]


def ok(*args: str) -> str:
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 0, result.output
    return result.stdout


def test_parse_keeps_a_400_digit_frame_index_and_reads_no_frame():
    result = CliRunner().invoke(app, ["parse", "--parser", "official", "--condition", "a"], input=ANSWERS[0][1])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    out = json.loads(result.stdout)
    assert out["status"] == "out_of_range"
    assert out["selected_image"] == int(BIG)
    assert "400-digit integer outside [0, 29]" in out["reason"]


@pytest.mark.parametrize("parser", ["official", "robopoint", "rescale-1000"])
def test_every_command_reads_a_run_holding_huge_numbers(parser, tmp_path, write_answered_run, mini_root):
    run = write_answered_run(tmp_path / "run", ANSWERS)
    rescored = json.loads(ok("rescore", run, "--parser", parser, "--json"))
    assert rescored["n_rows"] == len(ANSWERS)
    again = run / f"rescored-{parser}"
    ok("score", "--predictions", again, "--dataset", mini_root, "--json")
    ok("report", again, "--bootstrap", "0", "--out", tmp_path / "report")
    assert (tmp_path / "report" / "report.html").is_file()
    ok("export", again, "--out", tmp_path / "official.json")
    ok("export", again, "--format", "long-csv", "--out", tmp_path / "long.csv")
    ok("compare", again, run, "--bootstrap", "0", "--out", tmp_path / "compare")

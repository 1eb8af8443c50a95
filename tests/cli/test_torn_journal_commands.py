"""Every command that reads ``results.jsonl`` reads a tail torn inside a character as the rows
before it, and stops at a damaged line before the last with the file and the line named.

``report``, ``rescore``, ``score``, ``compare`` and ``export`` (resuming a run is in
tests/run/test_disk_full.py). Before, each of them crashed with UnicodeDecodeError until the
file was edited by hand.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import PredictionsError

pytestmark = pytest.mark.timeout(120)

#: Complete rows, every answer holding multi-byte characters (answered, and one parse error).
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200, "note": "中 😀 é"}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 400, "note": "😀😀"}'),
    ("train_house_00000/0/front/c", "我看不出来 😀"),
]
#: The row the full disk cut: a whole row of its own, torn inside its last emoji.
TORN = ("train_house_00000/0/up/c", '{"x": 10, "y": 10, "note": "😀"}')


def _cut_inside_the_last_emoji(line: bytes) -> bytes:
    return line[: line.rindex("😀".encode()) + 2]


@pytest.fixture
def torn_run(tmp_path, write_answered_run) -> Path:
    """A run folder whose last line is cut inside a 4-byte character."""
    run = write_answered_run(tmp_path / "run", ANSWERS)
    scratch = write_answered_run(tmp_path / "scratch", [TORN])
    torn = _cut_inside_the_last_emoji((scratch / "results.jsonl").read_bytes())
    with open(run / "results.jsonl", "ab") as fh:
        fh.write(torn)
    with pytest.raises(UnicodeDecodeError):  # the premise: the tail is not text
        torn.decode()
    return run


def commands(run: Path, tmp_path: Path, mini_root: Path) -> dict[str, list[str]]:
    return {
        "report": ["report", str(run), "--out", str(tmp_path / "report"), "--bootstrap", "0", "--no-gallery"],
        "rescore": ["rescore", str(run), "--json"],
        "score": ["score", "--predictions", str(run), "--dataset", str(mini_root), "--json"],
        "compare": ["compare", str(run), str(run), "--bootstrap", "0"],
        "export": ["export", str(run), "--out", str(tmp_path / "official.json")],
    }


@pytest.mark.parametrize("command", ["report", "rescore", "score", "compare", "export"])
def test_a_tail_torn_inside_a_character_reads_as_the_rows_before_it(command, torn_run, tmp_path, mini_root):
    result = CliRunner().invoke(app, commands(torn_run, tmp_path, mini_root)[command])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 0, result.output
    if command == "rescore":
        assert json.loads(result.stdout)["n_rows"] == len(ANSWERS)
    if command == "export":
        exported = json.loads((tmp_path / "official.json").read_text())
        rows = exported["predictions"] if isinstance(exported, dict) else exported
        assert len(rows) == len(ANSWERS)


@pytest.mark.parametrize("command", ["report", "rescore", "score", "compare", "export"])
def test_a_bad_byte_before_the_last_line_is_named_with_its_line(command, tmp_path, write_answered_run, mini_root):
    run = write_answered_run(tmp_path / "run", ANSWERS)
    lines = (run / "results.jsonl").read_bytes().splitlines(keepends=True)
    lines[1] = lines[1].replace("😀".encode(), b"\xf0\x9f", 1)  # a character missing its last two bytes
    (run / "results.jsonl").write_bytes(b"".join(lines))
    result = CliRunner().invoke(app, commands(run, tmp_path, mini_root)[command])
    assert isinstance(result.exception, PredictionsError), repr(result.exception)
    message = str(result.exception)
    assert f"{run / 'results.jsonl'}: line 2: byte 0xf0 at column" in message
    assert "\n" not in message

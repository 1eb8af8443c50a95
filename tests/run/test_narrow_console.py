"""Shortening a path for a narrow terminal: start and end kept, the middle cut (povagent/run/narrow_console.py)."""

from __future__ import annotations

import io
import re

import pytest

from povagent.run.narrow_console import ELLIPSIS, middle_ellipsis

PATH = "/home/someone/experiments/povbench/runs/2026-11-22/gpt-5.4-spatial-cot"


def test_a_text_that_fits_is_unchanged():
    assert middle_ellipsis("runs/a", 6) == "runs/a"


@pytest.mark.parametrize("width", [5, 20, 40, len(PATH) - 1])
def test_a_long_path_keeps_its_start_and_the_larger_share_of_its_end(width):
    short = middle_ellipsis(PATH, width)
    assert len(short) == width and short.count(ELLIPSIS) == 1
    head, tail = short.split(ELLIPSIS)
    assert PATH.startswith(head) and PATH.endswith(tail) and len(tail) >= len(head)


def test_no_room_gives_the_ellipsis_alone():
    assert middle_ellipsis(PATH, 1) == ELLIPSIS and middle_ellipsis(PATH, 0) == ""


def test_the_progress_bar_fits_80_columns_with_a_long_run_folder(monkeypatch):
    from povagent.run.progress import RichProgress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    screen = Tty()
    monkeypatch.setattr("sys.stderr", screen)
    monkeypatch.setenv("COLUMNS", "80")
    progress = RichProgress(PATH)
    progress.start(1800, 100)
    for status in ["answered"] * 50 + ["parse_error"] * 3 + ["infra_error"] * 2:
        progress.advance(status)
    progress.concurrency(4, 16)
    progress.stop()
    lines = re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", screen.getvalue()).replace("\r", "\n").splitlines()
    assert max(len(line) for line in lines) <= 80
    last = "\n".join(lines[-4:])
    assert "155/1800" in last and "spatial-cot" in last and "ETA" in last
    assert "infra_error=2" in last and "parse_error=3" in last and "4/16" in last

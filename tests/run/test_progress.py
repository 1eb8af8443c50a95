"""Progress: silent when not on a terminal (CI), a live bar otherwise."""

from __future__ import annotations

import io

from povagent.run.progress import QuietProgress, RichProgress, make_progress


def test_not_a_tty_gives_quiet_progress(monkeypatch):
    monkeypatch.setattr("sys.stderr", io.StringIO())
    progress = make_progress("run")
    assert isinstance(progress, QuietProgress)
    progress.start(3, 0)
    progress.advance("answered")
    progress.advance("infra_error")
    progress.stop()
    assert progress.counts == {"answered": 1, "infra_error": 1}


def test_quiet_flag_wins_on_a_tty(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr("sys.stderr", Tty())
    assert isinstance(make_progress("run", quiet=True), QuietProgress)
    assert isinstance(make_progress("run"), RichProgress)


def test_live_bar_shows_done_total_and_error_counts(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self):
            return True

    screen = Tty()
    monkeypatch.setattr("sys.stderr", screen)
    progress = make_progress("run")
    progress.start(3, 1)  # one key already done (resumed)
    progress.advance("answered")
    progress.advance("parse_error")
    progress.stop()
    shown = screen.getvalue()
    assert "3/3" in shown and "parse_error=1" in shown and "answered=" not in shown

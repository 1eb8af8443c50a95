"""The gallery draws each system's first run: when a system ran more than once, the page says so."""

from __future__ import annotations

from types import SimpleNamespace

from povagent.report.gallery_runs import run_shown_note
from povagent.report.html import render_page


def observations(runs_by_system: dict[str, list[int]]) -> list[SimpleNamespace]:
    return [SimpleNamespace(system=s, run=r) for s, runs in runs_by_system.items() for r in runs for _ in range(2)]


def test_a_system_run_three_times_is_said_to_show_its_first_run():
    note = run_shown_note(observations({"gpt-5.4/cot": [0, 1, 2], "random": [0, 1, 2]}), ["gpt-5.4/cot", "random"])
    assert note.startswith("The gallery draws one run per system: run 0 of 3 runs (gpt-5.4/cot, random).")


def test_systems_run_once_need_no_note():
    assert run_shown_note(observations({"gpt-5.4/cot": [0], "random": [0]}), ["gpt-5.4/cot", "random"]) == ""


def test_the_page_shows_the_note_above_the_gallery():
    gallery = {"systems": ["m/s"], "entries": [], "run_note": "The gallery draws one run per system: run 0 of 3 runs (m/s)."}
    page = render_page("t", "s", "", gallery)
    note = page.split('id="run-note">', 1)[1].split("</p>", 1)[0]
    assert note == "The gallery draws one run per system: run 0 of 3 runs (m/s)."

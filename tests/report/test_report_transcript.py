"""A multi-turn strategy's rows carry every request and answer, and the report's card shows
them as a transcript (loaded with the raw answers, not inlined), checked in headless Chromium."""

from __future__ import annotations

import html
import re
import shutil
from pathlib import Path

import pytest
import yaml
from test_report_html import VIEWER_SETTLED, dump  # the Chromium helpers

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.results.rows import read_rows
from povagent.results.transcript import transcripts
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer

TWO_TURNS = Path(__file__).resolve().parents[1] / "strategies" / "two_turn_strategy.py"
KEY_VARIABLE = "POVAGENT_TRANSCRIPT_KEY"
FIRST, SECOND = '{"x": 11, "y": 22} (first look)', '{"x": 33, "y": 44} (after checking)'


def answer(recorded) -> str:
    """Turn 1 (one user message): FIRST; turn 2 (user, assistant, user): SECOND."""
    return FIRST if len(recorded.body["messages"]) == 1 else SECOND


@pytest.fixture(scope="module")
def two_turn_report(tmp_path_factory):
    from povagent.testing.pytest_plugin import write_release

    root = tmp_path_factory.mktemp("transcript")
    release = write_release(root / "dataset", houses=1, pairs=1, pair_directions=1, frames=3)
    pipeline = root / "pipeline.yaml"
    shutil.copy(TWO_TURNS, root / TWO_TURNS.name)  # a config loads .py plugins only from its own folder
    with LoopbackServer(reply=answer, max_lifetime_s=120) as server, pytest.MonkeyPatch.context() as mp:
        mp.setenv(KEY_VARIABLE, "sk-test")
        pipeline.write_text(yaml.safe_dump({
            "plugins": [TWO_TURNS.name], "dataset": {"path": str(release)}, "strategy": "check-twice", "parser": "official",
            "backend": {"name": "litellm", "options": {"model": "openai/loopback-model", "api_base": server.url, "api_key_env": KEY_VARIABLE}},
            "instances": {"conditions": ["c"]}, "retry": {"attempts": 1}, "timeout": 20, "output": str(root / "run"),
        }))  # fmt: skip
        result = run_pipeline(load_pipeline(pipeline))
    rows = read_rows(result.run_dir / "results.jsonl")
    report = write_report(result.run_dir, root / "report", n_boot=50)
    return rows, report, root


def test_each_exchange_of_a_row_keeps_the_request_it_answered(two_turn_report):
    rows, _, _ = two_turn_report
    (row,) = rows
    first, second = row.exchanges
    assert (first.raw, second.raw) == (FIRST, SECOND) and row.prediction.x == 33
    assert first.prompt.startswith("--- user ---\nImage:\n[image: observer view]\n") and first.prompt.count("--- ") == 1
    # turn 2 keeps what it added to turn 1's messages: the model's real answer (no placeholder), the check
    assert second.prompt_continues and second.prompt.startswith("--- assistant ---\n" + FIRST + "\n--- user ---\nCheck that point")
    assert "<<" not in second.prompt
    assert transcripts(row.exchanges) == [first.prompt, first.prompt + "\n" + second.prompt]  # each request as sent


def test_the_card_shows_every_turn_in_chromium_and_the_page_does_not_inline_it(two_turn_report, browser):
    rows, report, _ = two_turn_report
    page = report.page.read_text(encoding="utf-8")
    assert "Check that point" not in page and "(first look)" not in page  # loaded lazily from answers/*.js
    assert any("Check that point" in f.read_text(encoding="utf-8") for f in (report.page.parent / "answers").glob("*.js"))
    dom = dump(browser, report.page, "open=0", until=VIEWER_SETTLED)
    transcript = re.search(r'<details class="transcript" data-turns="2"[^>]*>(.*?)</details>', dom, re.S)
    assert transcript, dom[-3000:]
    turns = re.findall(r'<div class="turn" data-turn="(\d)">.*?<pre class="turn-q">(.*?)</pre>.*?<pre class="turn-a">(.*?)</pre>', transcript.group(1), re.S)
    assert [t[0] for t in turns] == ["1", "2"]
    (_, q1, a1), (_, q2, a2) = ((n, html.unescape(q), html.unescape(a)) for n, q, a in turns)
    assert (a1, a2) == (FIRST, SECOND)
    assert [q1, q2] == transcripts(rows[0].exchanges)  # each request as sent, rebuilt
    assert "[image: " in q1 and "--- assistant ---\n" + FIRST in q2

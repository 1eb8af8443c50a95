"""A run parses and scores each answer in a worker thread, never on its event loop, and hands a
parser no reply longer than the bound."""

from __future__ import annotations

import textwrap

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.results.plugin_errors import MAX_REPLY_CHARS
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(120)

WHERE_PARSED = '''
import asyncio, json
from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer, ParseStatus, unparseable
from povagent.interfaces import Parser

class WhereParser(Parser):
    """Answers the centre when no event loop runs in its thread; else no answer, saying so."""
    answer_types = frozenset({"point"})
    def parse(self, text, spec):
        try:
            asyncio.get_running_loop()
        except RuntimeError:
            point = json.loads(text)
            return ParsedAnswer(status=ParseStatus.OK, selected_image=point.get("selected_image"), x=point["x"], y=point["y"])
        return unparseable("parsed on the event loop")

@hookimpl
def register_parsers(register):
    register("test-where-parsed", WhereParser, description="test: where it runs")
'''


def test_every_answer_is_parsed_where_no_event_loop_runs(tmp_path, write_pipeline, offline_plugin):
    plugin = tmp_path / "where_parsed.py"
    plugin.write_text(textwrap.dedent(WHERE_PARSED))
    config = write_pipeline(plugins=[offline_plugin.__file__, str(plugin)], parser="test-where-parsed", instances={"limit": 4})
    run_pipeline(load_pipeline(config))
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    assert len(rows) == 4 and [r.parse.reason for r in rows if r.status != "answered"] == []


def test_a_reply_longer_than_the_bound_is_a_non_response_never_parsed(tmp_path, write_pipeline, offline_plugin):
    # the reply is '{"x": 1, "y": 1}' and MAX_REPLY_CHARS spaces, padded by the backend
    options = {"reply": '{"x": 1, "y": 1}', "pad": MAX_REPLY_CHARS}
    run_pipeline(load_pipeline(write_pipeline(backend={"name": "test-center", "options": options}, instances={"limit": 1})))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "parse_error" and f"longer than the {MAX_REPLY_CHARS}" in row.parse.reason

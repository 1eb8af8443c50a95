"""One active row stays under its bound whatever a model sends each turn, keeps each message
once, and rebuilds every request as sent; the turn limit has a ceiling, refused at load."""

from __future__ import annotations

import json
from pathlib import Path
from typing import ClassVar

import pytest
import yaml

from povagent import hookimpl
from povagent.config.pipeline import load_pipeline
from povagent.errors import PluginError
from povagent.exchange.messages import Request, Response, ToolCall, Usage
from povagent.interfaces import Backend
from povagent.results.rows import read_rows
from povagent.results.transcript import transcripts
from povagent.run.runner import run_pipeline
from povagent_plugins.strategies.active import MAX_ACTIONS, MAX_TURNS, ROW_BOUND_BYTES

pytestmark = pytest.mark.timeout(120)


class Scripted(Backend):
    """Answers each turn with ``make(turn)``; keeps every request it was sent."""

    cacheable = False
    make = staticmethod(lambda turn: Response(""))
    requests: ClassVar[list[Request]] = []

    def __init__(self, **_) -> None:
        pass

    def identity(self):
        return {"backend": "scripted"}

    async def complete(self, request: Request, images) -> Response:
        type(self).requests.append(request)
        return type(self).make(len(type(self).requests))


@pytest.fixture
def scripted(povagent_host):
    class Plugin:
        @hookimpl
        def register_backends(self, register):
            register("scripted", Scripted)

    Scripted.requests = []
    povagent_host.add_plugin(Plugin(), name="scripted")
    try:
        yield Scripted
    finally:
        povagent_host.remove_plugin("scripted")


def write_pipeline(dataset: Path, folder: Path, **strategy) -> Path:
    doc = {
        "dataset": {"path": str(dataset)},
        "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
        "backend": "scripted",
        "strategy": {"name": "active", "options": strategy},
        "parser": "active",
        "scorers": ["official"],
        "retry": {"attempts": 1},
        "output": str(folder),
    }
    path = folder.parent / "pipeline.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def padded_calls(turn: int) -> Response:
    """128 padded calls (ids, names and arguments longer than any bound) and a long text."""
    pad = "x" * 5000
    calls = tuple(ToolCall(f"{turn}-{k}-{pad}", f"turn{pad}", json.dumps({"degrees": 1, "pad": pad})) for k in range(128))
    return Response(text="y" * 50_000, usage=Usage(1, 1, 0.0), tool_calls=calls)


def test_one_row_stays_under_its_bound_at_the_largest_budget_against_128_padded_calls_a_turn(generated_release, tmp_path, scripted):
    scripted.make = staticmethod(padded_calls)
    run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run", max_actions=MAX_ACTIONS, max_turns=MAX_TURNS)))
    line = (tmp_path / "run" / "results.jsonl").read_bytes()
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert len(scripted.requests) == MAX_TURNS and len(row.exchanges) == MAX_TURNS + 1  # every turn taken, and the record
    assert len(line) < ROW_BOUND_BYTES


def test_each_message_is_kept_once_and_every_request_is_rebuilt_as_sent(generated_release, tmp_path, scripted):
    turns = [Response("", tool_calls=(ToolCall("a", "turn", '{"degrees": 1, "x": 1}'), ToolCall("b", "fly", "{}"))),
             Response("thinking", tool_calls=(ToolCall("c", "ask", '{"question": "Where were you?"}'),)),
             Response("", tool_calls=(ToolCall("d", "answer", '{"image": "frame 0", "x": 1, "y": 2}'),))]  # fmt: skip
    scripted.make = staticmethod(lambda turn: turns[turn - 1])
    run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run")))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    rebuilt = transcripts(row.exchanges)
    assert rebuilt[:3] == [r.as_text() for r in scripted.requests] and rebuilt[3] == rebuilt[2]
    assert [e.prompt_continues for e in row.exchanges] == [False, True, True, True]
    first = row.exchanges[0].prompt
    assert all(first not in e.prompt for e in row.exchanges[1:])  # the first message is kept once
    assert row.exchanges[0].image_hashes == scripted.requests[0].image_hashes() and row.exchanges[1].image_hashes == []


def test_a_turn_limit_above_its_ceiling_is_refused_when_the_pipeline_loads(generated_release, tmp_path, scripted):
    with pytest.raises(PluginError, match=f"max_turns must be at most {MAX_TURNS}"):
        run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run", max_turns=MAX_TURNS + 1)))
    assert not (tmp_path / "run").exists() and scripted.requests == []

"""A strategy may talk to the model more than once (``Strategy.solve``), through the real runner.

The strategy below is the kind the interface exists for: it asks the paper's basic prompt, and
when the answer is out of range it shows the model its answer and asks once more. Registered as
a throwaway plugin, it runs through ``povagent``'s runner with the queued (canned-reply) backend.
"""

from __future__ import annotations

from dataclasses import replace

import yaml

from povagent import hookimpl
from povagent.answers.spec import ParseStatus
from povagent.config.pipeline import load_pipeline
from povagent.exchange.messages import Message
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent_plugins.parsers.json_answer import JsonAnswerParser
from povagent_plugins.strategies.basic import BasicStrategy

INSTANCE = "train_house_00000/0/right/c"


class SelfCheckingStrategy(BasicStrategy):
    """Basic prompt; an out-of-range answer is sent back once with a request to fix it."""

    async def solve(self, instance, ask, images):
        first = self.build(instance, images)
        answer = await ask(first)
        if JsonAnswerParser().parse(answer.text, first.answer).status is not ParseStatus.OUT_OF_RANGE:
            return [(first, answer)]
        follow_up = replace(
            first,
            messages=first.messages
            + (Message.text("assistant", answer.text), Message.text("user", "That point is outside the image. Answer again.")),
        )
        return [(first, answer), (follow_up, await ask(follow_up))]


class SelfCheckingPlugin:
    @hookimpl
    def register_strategies(self, register):
        register("self-check", SelfCheckingStrategy, description="basic prompt, one retry on an out-of-range answer")


def run_self_check(tmp_path, mini_root, povagent_host):
    povagent_host.add_plugin(SelfCheckingPlugin(), name="self-check-plugin")
    try:
        path = tmp_path / "pipeline.yaml"
        path.write_text(yaml.safe_dump({
            "dataset": {"path": str(mini_root)},
            "instances": {"conditions": ["c"], "directions": ["right"], "houses": ["train_house_00000"]},
            "backend": {"name": "queued"},
            "strategy": "self-check",
            "parser": "json",
            "concurrency": 1,
            "output": str(tmp_path / "run"),
        }))
        run_pipeline(load_pipeline(path))
    finally:
        povagent_host.remove_plugin("self-check-plugin")
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    return row


def test_a_multi_turn_strategy_asks_twice_and_the_last_answer_is_scored(tmp_path, mini_root, povagent_host, queued_backend):
    queued_backend.queue('{"x": 734, "y": 402}', '{"x": 376, "y": 206}')
    row = run_self_check(tmp_path, mini_root, povagent_host)
    assert row.instance_id == INSTANCE and row.status == "answered"
    assert [e.raw for e in row.exchanges] == ['{"x": 734, "y": 402}', '{"x": 376, "y": 206}']
    assert (row.parse.status, row.prediction.x, row.prediction.y) == ("ok", 376.0, 206.0)
    second = queued_backend.requests[1]
    assert [m.role for m in second.messages] == ["user", "assistant", "user"]
    assert second.messages[1].parts[0].text == '{"x": 734, "y": 402}'


def test_a_multi_turn_strategy_may_stop_after_one_turn(tmp_path, mini_root, povagent_host, queued_backend):
    queued_backend.queue('{"x": 300, "y": 200}')
    row = run_self_check(tmp_path, mini_root, povagent_host)
    assert len(row.exchanges) == 1 and len(queued_backend.requests) == 1
    assert row.parse.status == "ok"

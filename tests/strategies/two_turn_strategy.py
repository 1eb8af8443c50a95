"""A two-turn strategy plugin for the tests (named by path under a pipeline's ``plugins:``).

Turn 1 is the paper's basic request; turn 2 shows the model its answer and asks it to check
the point and answer again. ``plan_turns`` builds turn 2 from the same method as ``solve``,
with the placeholder for the earlier answer, so what is shown before the run is what is sent.
"""

from __future__ import annotations

from dataclasses import replace

from povagent import hookimpl
from povagent.exchange.messages import Message, Request
from povagent.interfaces import PlannedTurn, earlier_answer
from povagent_plugins.strategies.basic import BasicStrategy

#: What turn 2 asks after the model's first answer.
CHECK_AGAIN = "Check that point against the sentence once more, then answer again in the same JSON format."


class TwoTurnStrategy(BasicStrategy):
    """Basic prompt, then the model's answer shown back with a request to check it (always)."""

    def second(self, first: Request, first_answer: str) -> Request:
        """Turn 2: turn 1's messages, the model's answer, and the request to check it."""
        return replace(first, messages=first.messages + (Message.text("assistant", first_answer), Message.text("user", CHECK_AGAIN)))

    def plan_turns(self, instance, images):
        first = self.build(instance, images)
        return [PlannedTurn(first), PlannedTurn(self.second(first, earlier_answer(1)))]

    async def solve(self, instance, ask, images):
        first = self.build(instance, images)
        answer = await ask(first)
        follow_up = self.second(first, answer.text)
        return [(first, answer), (follow_up, await ask(follow_up))]


@hookimpl
def register_strategies(register) -> None:
    register("check-twice", TwoTurnStrategy, description="basic prompt, then its answer shown back to be checked")


"""``ask(question)``: ask the person who spoke; the simulated speaker answers from the pair's facts."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from povagent import hookimpl
from povagent.active.tools import EpisodeState, InvalidCall, Told, Tool

#: The longest question passed to the speaker (the longest arguments text read is the bound
#: every answer's calls are cut to: :data:`povagent.engine.received.MAX_ARGUMENTS_CHARS`).
MAX_QUESTION_CHARS = 500


@dataclass(frozen=True)
class Ask:
    """``ask(question)``."""

    question: str


def read(args: Mapping[str, Any]) -> Ask | InvalidCall:
    """The question: a string of at most :data:`MAX_QUESTION_CHARS` characters."""
    question = args["question"]
    if not isinstance(question, str):
        return InvalidCall(f"question must be a string, got {type(question).__name__}")
    if len(question) > MAX_QUESTION_CHARS:
        return InvalidCall(f"question longer than {MAX_QUESTION_CHARS} characters")
    return Ask(question)


def run(state: EpisodeState, call: Ask) -> Told:
    """The speaker's words."""
    return Told(state.speaker.answer(call.question), question=True)


TOOL = Tool(
    description="Ask the person who spoke a question; they say what they were doing, where, and what they faced, nothing more.",
    parameters={"question": {"type": "string"}},
    read=read,
    run=run,
    prose="asks the person who spoke",
    explained="the speaker answers from the pair's facts only: what they were doing and at which furniture (the Stated "
    "sentence), which object they faced (the anchor); anything else gets \"I can't say more.\" The answers are templated: no model",
)


@hookimpl
def register_tools(register) -> None:
    """Contribute ``ask``."""
    register("ask", TOOL)

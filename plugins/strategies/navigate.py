"""The ``navigate`` strategy and parser: the model walks to where the target is and says so.

The paper leaves navigation to future work (Limitations, second); on povagent's own houses it
is the active mode with another end. The episode is the ``active`` strategy's (the same first
message, views, budget and limits), but the tools offered are the navigate task's
(:attr:`povagent.active.tools.Tool.tasks`): ``turn``, ``tilt``, ``move`` and ``ask``, and
``arrived()`` in place of ``answer`` (no ``go_to_frame``: a jump is no walk). The robot's
pose when it calls ``arrived`` is the answer; the ``navigate`` parser reads it and the path
walked from the episode record, and the ``navigate`` scorer judges the arrival (within 1 m of
the target, the target in view) and weighs it by path length (SPL).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.active.live_episode import ARRIVED, Episode
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Message
from povagent.interfaces import Parser
from povagent.results.episode import EpisodeRecord, read_record
from povagent_plugins.strategies.active import MAX_RECORD_CHARS, ActiveStrategy, preamble
from povagent_plugins.strategies.layout import prompt_message

#: The default action budget of a walk (a house is crossed in a few moves and turns).
NAVIGATE_BUDGET = 16
#: What the model is told after the condition's prompt: the task is to walk, not to point.
INSTRUCTION = (
    "\n\nThis is a navigation task: do not answer with a pixel. Walk to where the target is, until you stand "
    "within 1 m of it and see it in your view, then call arrived()."
)

#: Where a Given (C) walk starts, as the preamble says it (the observer view is the speaker's).
GIVEN_START = "You start just inside the house's entrance, not where the observer view above was taken"


class NavigateStrategy(ActiveStrategy):
    """The navigate task in active mode: walk to the target, then ``arrived()``."""

    answer_parser = "navigate"
    answer_type = "walk"
    task = "navigate"

    def __init__(self, max_actions: int = NAVIGATE_BUDGET, **active: Any) -> None:
        super().__init__(max_actions=max_actions, **active)

    def first_message(self, instance: Instance, images: ImageStore) -> Message:
        """The condition's prompt with its images, the navigation instruction, the tools preamble."""
        n = len(self.shown_frames(instance))
        given = not instance.povbench_condition.uses_exploration_frames
        start = GIVEN_START if given else None
        text = self.prompt_text(instance) + INSTRUCTION + preamble(self.max_actions, n, given, self.tools(), start)
        return prompt_message(instance, self.images_for(instance, images), text, self.prompts.given_label)

    def episode(self, instance: Instance, images: ImageStore) -> Episode:
        """The active episode; in Given (C) it starts at the house's entrance, not at the
        observer's standpoint (the speaker's place, often no place for the robot)."""
        episode = super().episode(instance, images)
        if not instance.povbench_condition.uses_exploration_frames:
            from povagent.active.navigation import entrance_pose, house_of

            episode.start = episode.pose = entrance_pose(house_of(instance), episode.start)
        return episode

    def _text_answer(self, instance: Instance, episode: Episode, text: str, spec: AnswerSpec) -> None:
        """A reply without tool calls ends the walk with no arrival (a pixel is no answer here)."""
        episode.stop("no arrival: the model replied without calling arrived")


def walked(record: EpisodeRecord) -> list[tuple[float, float]]:
    """The floor positions (x, z) of an episode, start first, each once in a row."""
    path = [(record.start.x, record.start.z)]
    for step in record.steps:
        if step.pose is not None and (step.pose.x, step.pose.z) != path[-1]:
            path.append((step.pose.x, step.pose.z))
    return path


class NavigateParser(Parser):
    """Reads the episode record the ``navigate`` strategy leaves: the arrival and the path."""

    answer_types = frozenset({"walk"})
    reproduces_official = True
    reads = "the episode record the `navigate` strategy leaves as a row's final answer: the pose the robot called `arrived` in and the path it walked"
    beside_official = "its own reference: navigation has no official runner, so no second reading is kept"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Where the walk ended (its camera), the path walked and, as ``span``, whether it ended
        with ``arrived`` (never raises). An episode that ends without arriving is read too, as
        navigation counts it: a failure where it stopped, not a missing answer."""
        record = read_record(text[:MAX_RECORD_CHARS]) if isinstance(text, str) else None
        if record is None:
            return unparseable("not an active episode record (use the navigate strategy with the navigate parser)")
        final = next((s.pose for s in reversed(record.steps) if s.pose is not None), record.start)
        span = ARRIVED if record.end == ARRIVED else f"no arrival: {record.end or 'no end recorded'}"
        return ParsedAnswer(status=ParseStatus.OK, span=span, camera=final, path=walked(record))


@hookimpl
def register_strategies(register) -> None:
    """Contribute the navigate strategy."""
    register("navigate", NavigateStrategy, description="Navigation (active mode): walk to where the target is, then arrived()")


@hookimpl
def register_parsers(register) -> None:
    """Contribute the navigate parser (reads the navigate strategy's episode record)."""
    register("navigate", NavigateParser, description="The navigate strategy's episode record: the arrival pose and the path walked")

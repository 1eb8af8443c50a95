"""One active episode: the budget, the numbered views, and every call turned into an observation.

What it is for: the strategy hands each turn's tool calls here and gets back one observation per
call (the text of its tool result, and the view it rendered, if any). Each call is read and run
by the tool it names of the set the episode is given (:mod:`.tools`: the registered ones), and
the episode applies what the tool returns: a new pose is rendered as the next view (views are
numbered from 1 in the order returned across the episode), words go back as they are, the
final answer ends the episode. Every call but a valid one of a tool that ``ends`` the episode
counts against the budget (``max_actions``), invalid ones included; once it is used up further
calls are refused without running, so no model can make an episode render more than its budget
or run past its wall-clock limit. What it must not do: name a tool, talk to a model, touch the
image store or write files (the ``render`` callable it is given does).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from povagent.active.pose import Pose
from povagent.active.speaker import PairFacts
from povagent.active.tools import Answered, Arrived, InvalidCall, Moved, Told, Tool, ToolSet, read_call
from povagent.answers.spec import AnsweredCamera
from povagent.exchange.messages import ToolCall

if TYPE_CHECKING:  # the floor needs the generator: loaded with the house, not with this module
    from povagent.active.floor import Floor
from povagent.results.episode import EpisodeAnswer, EpisodeCounts, EpisodeRecord, Step, ViewRecord

#: The default action budget (``answer`` not counted).
DEFAULT_BUDGET = 8
#: The most characters of a call's arguments a step keeps (and the conversation sent back, and
#: so the row's transcript: :func:`kept_call`), and the most steps a record keeps (the rest are
#: counted in ``steps_dropped``): a record's size is bounded whatever a model sends.
KEPT_ARGUMENTS = 256
MAX_RECORDED_STEPS = 256

#: How an episode of the navigate task ends when the robot says it has arrived.
ARRIVED = "arrived"

#: Renders a pose: returns the view PNG's SHA-256 (the caller stores the bytes).
RenderFn = Callable[[Pose], str]


def kept_call(call: ToolCall) -> ToolCall:
    """A call as the episode keeps it in the conversation: its arguments cut to
    :data:`KEPT_ARGUMENTS` (a valid call's are far shorter; the call is run on the whole text)."""
    return call if len(call.arguments) <= KEPT_ARGUMENTS else ToolCall(call.id, call.name, call.arguments[:KEPT_ARGUMENTS])


@dataclass(frozen=True)
class Observation:
    """What one call gave back: the tool result text, and the view it rendered (number, SHA-256)."""

    call_id: str
    text: str
    view: int | None = None
    sha256: str | None = None
    pose: Pose | None = None


def camera_record(pose: Pose) -> AnsweredCamera:
    """A pose as the record (and the scorer) holds a camera."""
    return AnsweredCamera(x=pose.x, y=pose.y, z=pose.z, yaw=pose.yaw, horizon=pose.horizon, fov=pose.fov, width=pose.width, height=pose.height)


class Episode:
    """The state of one episode; :meth:`handle` runs one turn's calls, in order."""

    def __init__(
        self,
        frames: Sequence[Pose],
        start: Pose,
        render: RenderFn,
        floor: Callable[[], Floor],
        speaker: PairFacts,
        tools: ToolSet,
        budget: int = DEFAULT_BUDGET,
        max_seconds: float = 600.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.tools = tools
        self.frames = tuple(frames)
        self.pose = start
        self.start = start
        self.budget = budget
        self._render = render
        self._floor_factory = floor
        self._floor: Floor | None = None
        self.speaker = speaker
        self._clock = clock
        self.deadline = clock() + max_seconds
        self.max_seconds = max_seconds
        self.views: list[ViewRecord] = []
        self.steps: list[Step] = []
        self.counts = EpisodeCounts()
        self.answer: EpisodeAnswer | None = None
        self.end = ""
        self.steps_dropped = 0

    @property
    def done(self) -> bool:
        """Whether the episode has ended (answered, or stopped by a limit)."""
        return bool(self.end)

    @property
    def budget_left(self) -> int:
        """Actions still allowed."""
        return max(0, self.budget - self.counts.actions)

    def state(self) -> dict[str, object]:
        """What offline explorers read (``Request.question``): poses of the frames and views."""
        return {
            "kind": "active",
            "frames": [camera_record(p).model_dump() for p in self.frames],
            "views": [{"n": v.n, "camera": v.camera.model_dump()} for v in self.views],
            "pose": camera_record(self.pose).model_dump(),
            "budget_left": self.budget_left,
            "actions": [s.action for s in self.steps if s.valid],
        }

    def stop(self, why: str) -> None:
        """End the episode without an answer (a limit was reached)."""
        if not self.end:
            self.end = why

    # -- one turn ------------------------------------------------------------------------------
    def handle(self, calls: Sequence[ToolCall], turn: int) -> list[Observation]:
        """Run ``calls`` in order; one observation each (calls after the end are not run)."""
        self.counts.turns = max(self.counts.turns, turn)
        out = []
        for call in calls:
            if not self.end and self._clock() > self.deadline:
                self.stop(f"no answer within the episode's time limit ({self.max_seconds:g} s)")
            out.append(self._one(call, turn))
        return out

    def floor(self) -> Floor:
        """The house's reachable floor, built on first use (a move needs it, a turn does not)."""
        if self._floor is None:
            self._floor = self._floor_factory()
        return self._floor

    def _one(self, call: ToolCall, turn: int) -> Observation:
        args = call.arguments[:KEPT_ARGUMENTS]
        if self.end:
            self._step(turn, call.name, args, False, "not run: the episode has ended", counted=False)
            return Observation(call.id, "not run: the episode has ended")
        read = read_call(call.name, call.arguments, self.tools)
        if not isinstance(read, InvalidCall) and read[0].ends:
            return self._ending(call, turn, *read)
        if self.budget_left == 0:
            self.counts.refused_over_budget += 1
            ending = " or ".join(n for n, t in self.tools.tools.items() if t.ends)
            text = f"not run: the budget of {self.budget} actions is used up; call {ending}"
            self._step(turn, call.name[:40], args, False, text, counted=False)
            return Observation(call.id, text)
        self.counts.actions += 1
        if isinstance(read, InvalidCall):
            return self._invalid(call, turn, read.reason)
        tool, typed = read
        effect = tool.run(self, typed)
        if isinstance(effect, InvalidCall):
            return self._invalid(call, turn, f"{call.name}: {effect.reason}")
        if isinstance(effect, Told):
            self.counts.questions += effect.question
            self._step(turn, call.name, args, True, effect.text)
            return Observation(call.id, effect.text)
        assert isinstance(effect, Moved) and tool.renders, f"tool {call.name!r} returned {effect!r} (renders={tool.renders})"
        self.pose = effect.pose
        self.counts.blocked_moves += effect.blocked
        view = self._view()
        text = f"View {view.n}: {effect.said}; now {self.pose.in_words(self.start)}"
        self._step(turn, call.name, args, True, text, view=view, blocked=effect.blocked)
        return Observation(call.id, text, view.n, view.sha256, self.pose)

    def _view(self) -> ViewRecord:
        sha = self._render(self.pose)
        view = ViewRecord(n=len(self.views) + 1, sha256=sha, camera=camera_record(self.pose))
        self.views.append(view)
        self.counts.views += 1
        return view

    def _invalid(self, call: ToolCall, turn: int, reason: str) -> Observation:
        self.counts.invalid_calls += 1
        text = f"invalid call: {reason}"
        self._step(turn, call.name[:40], call.arguments[:KEPT_ARGUMENTS], False, text)
        return Observation(call.id, text)

    def _ending(self, call: ToolCall, turn: int, tool: Tool, typed: object) -> Observation:
        """A call of a tool that ends the episode: not counted when valid; an invalid one counts,
        or is refused once the budget is used up."""
        effect = tool.run(self, typed)
        if isinstance(effect, InvalidCall):
            if self.budget_left == 0:  # an invalid answer cannot count any more: refused
                self.counts.refused_over_budget += 1
                text = f"not run: {effect.reason}, and the budget is used up"
                self._step(turn, call.name, call.arguments[:KEPT_ARGUMENTS], False, text, counted=False)
                return Observation(call.id, text)
            self.counts.actions += 1
            return self._invalid(call, turn, f"{call.name}: {effect.reason}")
        if isinstance(effect, Arrived):  # the pose it stands in is the answer: the record's last pose
            self.end = ARRIVED
            self._step(turn, call.name, call.arguments[:KEPT_ARGUMENTS], True, "arrival recorded", counted=False)
            return Observation(call.id, "arrival recorded")
        assert isinstance(effect, Answered), f"tool {call.name!r} ends the episode but returned {effect!r}"
        self.finish(effect.image, effect.x, effect.y, "answer_tool")
        self._step(turn, call.name, call.arguments[:KEPT_ARGUMENTS], True, "answer recorded", counted=False)
        return Observation(call.id, "answer recorded")

    def image_camera(self, kind: str, number: int) -> AnsweredCamera | None:
        """The camera of ``frame k`` or ``view n``, or ``None`` when no such image was shown."""
        if kind == "frame":
            return camera_record(self.frames[number]) if 0 <= number < len(self.frames) else None
        return self.views[number - 1].camera if 1 <= number <= len(self.views) else None

    def finish(self, image: str, x: float, y: float, via: str) -> None:
        """Record the answer (``image`` as ``frame k``/``view n``) and end the episode."""
        kind, number = image.split()
        camera = self.image_camera(kind, int(number))
        assert camera is not None, "finish() takes an image that was shown"
        frame = int(number) if kind == "frame" else None
        self.answer = EpisodeAnswer(image=image, x=x, y=y, via=via, camera=camera, frame=frame)
        self.end = "answered" if via == "answer_tool" else "answered in text (official JSON), not with the answer tool"

    def _step(
        self, turn: int, action: str, args: str, valid: bool, text: str, *, view: ViewRecord | None = None, blocked: bool = False, counted: bool = True
    ) -> None:
        if len(self.steps) >= MAX_RECORDED_STEPS:
            self.steps_dropped += 1
            return
        self.steps.append(
            Step(
                turn=turn,
                action=action,
                arguments=args,
                valid=valid,
                observation=text[:300],
                pose=camera_record(self.pose),
                view=view.n if view else None,
                sha256=view.sha256 if view else None,
                blocked=blocked,
                counted=counted,
            )
        )

    def record(self) -> EpisodeRecord:
        """The episode as the row keeps it."""
        return EpisodeRecord(
            budget=self.budget,
            shown_frames=len(self.frames),
            start=camera_record(self.start),
            steps=self.steps,
            views=self.views,
            counts=self.counts,
            answer=self.answer,
            end=self.end or "no answer",
            steps_dropped=self.steps_dropped,
        )

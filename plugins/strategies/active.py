"""The ``active`` strategy and parser: a model looks around a generated house through tool calls.

The first message is the condition's passive prompt (A/B: the first ``max_frames`` exploration
frames, labelled ``Image k``; C: the observer view) followed by the tools preamble, which
states the budget; every request offers the registered tools (``register_tools``: the built-ins
of :mod:`povagent_plugins.tools` and any plugin's, :mod:`povagent.active.tools`). Each turn's
calls run in an :class:`~povagent.active.live_episode.Episode`; each tool result goes back as a
``tool`` message, and each rendered view as an image labelled ``View n:`` in a user message
after them (tool messages carry no images). The episode ends with the ``answer`` call, or with
a text answer in the official JSON (accepted, and labelled so), or at a limit (the budget,
``max_turns``, ``max_seconds``). The row's final answer is the episode's record (trajectory,
counts, the answer and the camera of the image answered in); the ``active`` parser reads it,
and the official scorer scores it in that camera.

Options (besides the basic strategy's ``prompts``, ``max_tokens``, ``temperature``):
``max_frames`` (default 8: fewer frames than the house has, so looking matters; ``null``: all),
``max_actions`` (default 8, ``answer`` not counted; at most 64), ``max_turns`` (default
``max_actions`` + 2; at most 66), ``max_seconds`` (default 600: the episode's wall-clock limit).

One row stays under :data:`ROW_BOUND_BYTES` whatever a model sends: each turn's answer is
bounded where it enters (:mod:`povagent.engine.received`: 128 calls, their ids, names and
arguments, the text), the calls go back to the model with their arguments cut as the record
keeps them (:func:`~povagent.active.live_episode.kept_call`), the row keeps each turn's new messages
once (:mod:`povagent.results.transcript`), and the turns are bounded.
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from povagent import hookimpl
from povagent.active.live_episode import DEFAULT_BUDGET, Episode, kept_call
from povagent.active.pose import Pose
from povagent.active.speaker import SPEAKER_KNOWLEDGE, pair_facts
from povagent.active.tools import ToolSet
from povagent.active.views import ViewStore
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Request, Response, TextPart
from povagent.interfaces import Ask, Parser, PlannedTurn, earlier_answer
from povagent.plugins import get_plugin_host
from povagent.results.episode import read_record
from povagent_plugins.parsers.official import parse_official
from povagent_plugins.strategies.basic import BasicStrategy, _positive_or_none
from povagent_plugins.strategies.layout import prompt_message

if TYPE_CHECKING:
    from povagent.interfaces import LoadedPlugins

#: The largest record the parser reads (a budget of 64 actions stays far below it).
MAX_RECORD_CHARS = 4 * 1024 * 1024
#: The most actions and the most turns (model calls) an episode may be given.
MAX_ACTIONS = 64
MAX_TURNS = MAX_ACTIONS + 2
#: What one row of an episode stays under at any budget, whatever the model sends.
ROW_BOUND_BYTES = 8 * 1024 * 1024
#: The SHA-256 of the tools every active run offered before tools were registered (the six
#: built-ins' schemas, canonical JSON): a pipeline offering exactly these records nothing more
#: in its config hash.
REFERENCE_TOOLS_SHA256 = "257f62899100ef4dfb553c612d0f96277d80eb84049a1533677ce4b6ce176ec2"


def _words(names: list[str]) -> str:
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def preamble(budget: int, n_frames: int, given: bool, tools: ToolSet | None = None, start: str | None = None) -> str:
    """The tools preamble after the passive prompt: what the model may do (each tool's
    signature and prose, as registered), and its budget. ``start`` says where the episode
    starts when that is not where frame 0 was taken."""
    tools = tools if tools is not None else get_plugin_host().tools()
    shown = "the observer view above is frame 0" if given else f"the images above are frames 0-{n_frames - 1} (Image k is frame k)"
    start = start or f"You start where frame 0 was taken; {shown}"
    acting = [f"{t.signature(n)} {t.prose}" for n, t in tools.tools.items() if not t.ends]
    ending = [n for n, t in tools.tools.items() if t.ends]
    rendering = _words([n for n, t in tools.tools.items() if t.renders])
    finish = " or ".join(f"{tools[n].signature(n)}: {tools[n].prose}" for n in ending)
    return (
        f"\n\nYou may look around the house before you answer, with the tools offered: {'; '.join(acting)}. "
        f"Each {rendering} returns a new view, numbered View 1, View 2, ... in order. "
        f"{start}. You have {budget} actions ({_words(ending)} "
        f"{'is' if len(ending) == 1 else 'are'} not counted; invalid calls count). Finish with {finish}"
    )


class ActiveStrategy(BasicStrategy):
    """Active observer grounding: the passive prompt, then tools to look around before answering.

    ``speaker`` (default ``stated``) says what ``ask`` may tell: ``stated``, the Stated sentence
    and the furniture in every condition, so Inferred (A) nearly becomes Stated (B) once the
    model asks; ``condition``, only the condition's information (:mod:`povagent.active.speaker`).
    """

    default_max_tokens: int | None = 512
    default_max_frames: int | None = 8
    #: Only the ``active`` parser reads the episode record a row ends with.
    answer_parser = "active"
    #: The task whose tools an episode offers (:attr:`povagent.active.tools.Tool.tasks`).
    task = "point"

    def __init__(
        self, max_actions: int = DEFAULT_BUDGET, max_turns: int | None = None, max_seconds: float = 600.0, speaker: str = "stated", **basic: Any
    ) -> None:
        super().__init__(**basic)
        if speaker not in SPEAKER_KNOWLEDGE:
            raise ValueError(f"strategy option speaker must be one of {', '.join(SPEAKER_KNOWLEDGE)}, got {speaker!r}")
        self.speaker = speaker
        self.max_actions = _positive_or_none(max_actions, "max_actions", "the action budget") or DEFAULT_BUDGET
        if self.max_actions > MAX_ACTIONS:
            raise ValueError(f"strategy option max_actions must be at most {MAX_ACTIONS}, got {max_actions!r}")
        self.max_turns = _positive_or_none(max_turns, "max_turns", "default: max_actions + 2") or self.max_actions + 2
        if self.max_turns > MAX_TURNS:
            raise ValueError(f"strategy option max_turns must be at most {MAX_TURNS} (so one row stays under 8 MB), got {max_turns!r}")
        if isinstance(max_seconds, bool) or not isinstance(max_seconds, (int, float)) or not 0 < max_seconds <= 86400:
            raise ValueError(f"strategy option max_seconds must be a number in (0, 86400], got {max_seconds!r}")
        self.max_seconds = float(max_seconds)
        self._views: ViewStore | None = None
        self._tools: ToolSet | None = None
        self._scratch: tempfile.TemporaryDirectory[str] | None = None

    def use_run_folder(self, folder: Path) -> None:
        """Views go to ``RUN/views`` (content-addressed: a resumed run renders none again); a
        link planted there is refused now, in one line, before any episode runs."""
        self._views = ViewStore(Path(folder))

    def use_plugins(self, host: LoadedPlugins) -> None:
        """Offer the tools the run's plugins registered (its ``plugins:`` included)."""
        self._tools = host.tools(self.task)

    def tools(self) -> ToolSet:
        """The tools offered: the run's (:meth:`use_plugins`), else the process's registered ones."""
        if self._tools is None:
            self._tools = get_plugin_host().tools(self.task)
        return self._tools

    def identity(self) -> dict[str, Any]:
        """The tools offered, by the SHA-256 of their schemas, unless they are the reference set
        (:data:`REFERENCE_TOOLS_SHA256`): such a pipeline's config hash stays what it was before
        tools were registered, so those run folders resume; any other set never mixes with it."""
        digest = hashlib.sha256(json.dumps(self.tools().schemas(), sort_keys=True, separators=(",", ":")).encode()).hexdigest()
        return {} if digest == REFERENCE_TOOLS_SHA256 else {"tools": digest}

    def views(self) -> ViewStore:
        """The view store: the run folder's, else a private temporary one (tests, embedding)."""
        if self._views is None:
            self._scratch = tempfile.TemporaryDirectory(prefix="povagent-views-")
            self._views = ViewStore(Path(self._scratch.name))
        return self._views

    # -- the requests ---------------------------------------------------------------------------
    def first_message(self, instance: Instance, images: ImageStore) -> Message:
        """The passive prompt with its images, then the tools preamble."""
        n = len(self.shown_frames(instance))
        text = self.prompt_text(instance) + preamble(self.max_actions, n, not instance.povbench_condition.uses_exploration_frames, self.tools())
        return prompt_message(instance, self.images_for(instance, images), text, self.prompts.given_label)

    def _request(self, instance: Instance, messages: list[Message], state: dict[str, object] | None = None) -> Request:
        return Request(
            messages=tuple(messages),
            answer=self.answer_spec(instance),
            generation=self.generation,
            instance=instance,
            tools=self.tools().schemas(),
            question=state,
        )

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """The first request: the first message, with the tools offered."""
        return self._request(instance, [self.first_message(instance, images)])

    def plan_turns(self, instance: Instance, images: ImageStore) -> list[PlannedTurn]:
        """The first request, and the later turns taken while the model keeps calling tools."""
        first = self.first_message(instance, images)
        later = [
            first,
            Message.text("assistant", earlier_answer(1)),
            Message.text("user", "<<one tool result per call, then View n: with each view rendered>>"),
        ]
        note = f"taken while the model calls tools: at most {self.max_turns - 1} more turns"
        return [PlannedTurn(self._request(instance, [first])), PlannedTurn(self._request(instance, later), note=note)]

    # -- the episode ----------------------------------------------------------------------------
    def episode(self, instance: Instance, images: ImageStore) -> Episode:
        """A new episode of ``instance`` (rebuilds the house unless this process has it)."""
        # the renderer and the generator load here, with the first house (not with the plugin list)
        from povagent.active.floor import Floor
        from povagent.active.house import house_for

        if not instance.frames:
            raise ValueError(f"{instance.id}: no frames to start from")
        house_dir = instance.frames[0].file.parent.parent
        house = house_for(house_dir.parent.parent, instance.house_id)
        store = self.views()

        def render(pose: Pose) -> str:
            view = store.view(instance.house_id, pose, lambda p: house.render_png(p.camera()))
            images.add_file(view.path, view.png)  # the bytes checked against the hash, not read again
            return view.sha256

        frames = [Pose.of_camera(f.camera) for f in self.shown_frames(instance)]
        facts = pair_facts(house_dir, instance.house_id, instance.pair_id, instance.povbench_direction.value, instance.povbench_condition.value, self.speaker)
        return Episode(frames, frames[0], render, lambda: Floor(house.built.house), facts, self.tools(), self.max_actions, self.max_seconds)

    async def solve(self, instance: Instance, ask: Ask, images: ImageStore) -> list[tuple[Request, Response]]:
        """Run the episode: ask, run the calls, show the views, until it ends."""
        episode = await asyncio.to_thread(self.episode, instance, images)
        messages = [self.first_message(instance, images)]
        turns: list[tuple[Request, Response]] = []
        request = self._request(instance, messages, episode.state())
        for turn in range(1, self.max_turns + 1):
            if episode.done:
                break
            request = self._request(instance, messages, episode.state())
            response = await ask(request)
            turns.append((request, response))
            if not response.tool_calls:
                self._text_answer(instance, episode, response.text, request.answer)
                break
            said = (TextPart(response.text),) if response.text else ()
            messages.append(Message("assistant", said, tuple(kept_call(c) for c in response.tool_calls)))
            observations = await asyncio.to_thread(episode.handle, response.tool_calls, turn)
            messages += [Message("tool", (TextPart(o.text),), tool_call_id=o.call_id) for o in observations]
            shown: list[TextPart | ImagePart] = []
            for o in observations:
                if o.view is not None and o.sha256 is not None:
                    shown += [TextPart(f"View {o.view}: {o.text.split(': ', 1)[-1]}"), ImagePart(o.sha256, label=f"View {o.view}")]
            if shown:
                messages.append(Message("user", tuple(shown)))
        episode.stop(f"no answer within {self.max_turns} turns")
        final = Response(text=episode.record().model_dump_json(), by_strategy=True)
        return [*turns, (request, final)]

    def _text_answer(self, instance: Instance, episode: Episode, text: str, spec: AnswerSpec) -> None:
        """A reply without tool calls: the official JSON is accepted as the answer (labelled)."""
        parsed = parse_official(text, spec)
        if not parsed.answered or parsed.x is None or parsed.y is None:
            episode.stop("no answer: the model replied without a tool call or an answer in the official JSON")
            return
        frame = parsed.selected_image if instance.povbench_condition.uses_exploration_frames else 0
        if frame is None or episode.image_camera("frame", frame) is None:
            episode.stop(f"no answer: the text answer names no frame shown ({parsed.selected_image!r})")
            return
        episode.finish(f"frame {frame}", parsed.x, parsed.y, "text")


class ActiveParser(Parser):
    """Reads the episode record the ``active`` strategy leaves as a row's final answer.

    The active mode has no official runner to read otherwise: the ``answer`` call's values are
    the answer as given, so no second, "official" reading is kept beside this one.
    """

    reproduces_official = True
    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "the episode record the `active` strategy leaves as a row's final answer: the `answer` call's values and the camera of the image they were given in"
    beside_official = "its own reference: the active mode has no official runner, so no second reading is kept"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The answer and the camera of the image it was given in (never raises)."""
        record = read_record(text[:MAX_RECORD_CHARS]) if isinstance(text, str) else None
        if record is None:
            return unparseable("not an active episode record (use the active strategy with the active parser)")
        answer = record.answer
        if answer is None:
            return unparseable(record.end or "no answer")
        inside = 0 <= answer.x <= answer.camera.width - 1 and 0 <= answer.y <= answer.camera.height - 1
        return ParsedAnswer(
            status=ParseStatus.OK if inside else ParseStatus.OUT_OF_RANGE,
            selected_image=answer.frame,
            x=answer.x,
            y=answer.y,
            span=answer.image,
            repair="answered in text (official JSON), not with the answer tool" if answer.via == "text" else None,
            camera=answer.camera,
        )


@hookimpl
def register_strategies(register) -> None:
    """Contribute the active strategy."""
    register("active", ActiveStrategy, description="Active observer grounding: look around a generated house with tool calls, then answer")


@hookimpl
def register_parsers(register) -> None:
    """Contribute the active parser (reads the active strategy's episode record)."""
    register("active", ActiveParser, description="The active strategy's episode record: the answer and its image's camera")

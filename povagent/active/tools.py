"""What an active-mode tool is, the set an episode offers, and the reading of a call.

What it is for: a tool is contributed by a plugin (``register_tools``, the built-in ones by
``povagent_plugins.tools`` exactly as a third party's): it declares the schema the model is
offered (OpenAI function calling, sent by litellm as ``tools=``), how the preamble and the docs
describe it, how its arguments are read, and what it does to the episode (a typed function over
the episode's state returning an :data:`Effect`); the plugin host collects them
(:meth:`povagent.plugins.PluginHost.tools`). This module owns the one place a call the
model made is read. A call is untrusted output: an unknown name, missing or extra arguments, a
string where a number belongs, NaN, Infinity or 1e308, an over-long text, all become an
:class:`InvalidCall` with one line saying what was wrong, never an exception.

What it must not do: name a tool (the core knows kinds of effect, never tools), render or move.
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from povagent.engine.received import MAX_ARGUMENTS_CHARS

if TYPE_CHECKING:  # only for the types a tool function sees
    from povagent.active.floor import Floor
    from povagent.active.pose import Pose
    from povagent.active.speaker import PairFacts
    from povagent.answers.spec import AnsweredCamera


# -- what a call does to the episode ------------------------------------------------------------
@dataclass(frozen=True)
class Moved:
    """The robot stands in a new ``pose``: the episode renders the view there (``said`` is how
    the tool result begins, ``blocked`` whether a wall or furniture stopped it)."""

    pose: Pose
    said: str
    blocked: bool = False


@dataclass(frozen=True)
class Told:
    """The call is answered in words, no view (``question``: it was a question to the speaker)."""

    text: str
    question: bool = False


@dataclass(frozen=True)
class Answered:
    """The final answer: pixel (``x``, ``y``) in ``image`` (``frame k`` or ``view n``, shown)."""

    image: str
    x: float
    y: float


@dataclass(frozen=True)
class Arrived:
    """The navigate task's end: the robot says it stands where the target is (the pose it
    stands in is the answer)."""


@dataclass(frozen=True)
class InvalidCall:
    """A call that cannot be run: ``reason`` is the one line the model is told. A tool's own
    functions give the reason in its words; :func:`read_call` and the episode prefix its name."""

    reason: str


Effect = Moved | Told | Answered | Arrived


class EpisodeState(Protocol):
    """What a tool's :attr:`Tool.run` reads of the episode (it changes nothing itself)."""

    frames: tuple[Pose, ...]
    pose: Pose
    start: Pose
    speaker: PairFacts

    def floor(self) -> Floor:
        """The house's reachable floor (built on first use)."""
        ...

    def image_camera(self, kind: str, number: int) -> AnsweredCamera | None:
        """The camera of ``frame k`` or ``view n``, or ``None`` when no such image was shown."""
        ...


# -- a tool -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Tool:
    """One active-mode tool, as a plugin registers it: ``register(name, Tool(...))``.

    ``parameters`` are the JSON Schema of each argument, in the order the model sees them (all
    required, no others). ``read(arguments)`` turns the checked JSON object into the tool's
    typed arguments, or an :class:`InvalidCall` saying what is wrong; ``run(state, typed)``
    returns what the call does (:class:`Moved`, :class:`Told`, :class:`Answered`, :class:`Arrived`) or why it
    cannot run in this episode. ``renders``: the call returns a new view (its ``run`` returns
    :class:`Moved`). ``ends``: the call finishes the episode and is not counted against the
    budget. ``prose`` follows the tool's signature in the preamble; ``explained`` is its row of
    the docs table. ``explore(rng, state)``, when given, is the arguments a random explorer
    calls it with (``state`` is :meth:`Episode.state`). ``tasks`` names the tasks whose
    episodes offer the tool (``point``, ``navigate``; ``None``: every task): the final answer
    of one task is no tool of another.
    """

    description: str
    parameters: Mapping[str, Mapping[str, Any]]
    read: Callable[[Mapping[str, Any]], Any]
    run: Callable[[EpisodeState, Any], Effect | InvalidCall]
    prose: str
    explained: str
    renders: bool = False
    ends: bool = False
    explore: Callable[[random.Random, Mapping[str, Any]], dict[str, Any]] | None = None
    tasks: tuple[str, ...] | None = None

    def schema(self, name: str) -> dict[str, Any]:
        """The OpenAI function schema offered under ``name``."""
        properties = {k: dict(v) for k, v in self.parameters.items()}
        return {
            "type": "function",
            "function": {
                "name": name,
                "description": self.description,
                "parameters": {"type": "object", "properties": properties, "required": list(properties), "additionalProperties": False},
            },
        }

    def signature(self, name: str) -> str:
        """``name(arg, arg)``, as the preamble writes a call."""
        return f"{name}({', '.join(self.parameters)})"


class ToolSet:
    """The tools an episode offers, by name, in the order they were registered (``sources``:
    where each came from, as the plugin host names plugins)."""

    def __init__(self, tools: Iterable[tuple[str, Tool]], sources: Mapping[str, str] | None = None) -> None:
        self.tools: dict[str, Tool] = dict(tools)
        self.sources: dict[str, str] = dict(sources or {})

    @property
    def names(self) -> tuple[str, ...]:
        """The tools' names, in order."""
        return tuple(self.tools)

    def schemas(self) -> tuple[dict[str, Any], ...]:
        """The ``tools=`` list every request of an episode sends."""
        return tuple(tool.schema(name) for name, tool in self.tools.items())

    def for_task(self, task: str) -> ToolSet:
        """The tools an episode of ``task`` offers, in the same order."""
        kept = [(n, t) for n, t in self.tools.items() if t.tasks is None or task in t.tasks]
        return ToolSet(kept, {n: s for n, s in self.sources.items() if n in dict(kept)})

    def __getitem__(self, name: str) -> Tool:
        return self.tools[name]


# -- reading arguments: the rules every tool shares ---------------------------------------------
def number_argument(args: Mapping[str, Any], key: str, bound: float) -> float | str:
    """``args[key]`` as a finite float within ``[-bound, bound]``, or why it is not (a bool, a
    string, NaN, Infinity and an integer too large for a float are not numbers here)."""
    value = args[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"{key} must be a number, got {type(value).__name__}"
    if isinstance(value, int) and abs(value) > bound:  # checked as an integer: a 400-digit one has no float
        return f"{key} must lie within [-{bound:g}, {bound:g}], got an integer of {len(str(abs(value)))} digits"
    value = float(value)
    if not math.isfinite(value):
        return f"{key} must be a finite number, got {value}"
    if abs(value) > bound:
        return f"{key} must lie within [-{bound:g}, {bound:g}], got {value:g}"
    return value


def read_call(name: str, arguments: str, tools: ToolSet) -> tuple[Tool, Any] | InvalidCall:
    """The tool of ``tools`` a call names and its typed arguments, or why the call is invalid
    (never raises)."""
    if name not in tools.tools:
        return InvalidCall(f"unknown tool {name[:40]!r} (tools: {', '.join(tools.names)})")
    if len(arguments) > MAX_ARGUMENTS_CHARS:
        return InvalidCall(f"{name}: arguments longer than {MAX_ARGUMENTS_CHARS} characters")
    try:
        args = json.loads(arguments) if arguments.strip() else {}
    except (ValueError, RecursionError):
        return InvalidCall(f"{name}: arguments are not a JSON object")
    if not isinstance(args, dict):
        return InvalidCall(f"{name}: arguments are not a JSON object")
    tool = tools[name]
    wanted = tuple(tool.parameters)
    missing = [k for k in wanted if k not in args]
    extra = sorted(str(k)[:40] for k in args if k not in wanted)
    if missing or extra:
        said = [f"missing {', '.join(missing)}"] if missing else []
        said += [f"unexpected {', '.join(extra[:5])}"] if extra else []
        return InvalidCall(f"{name}: {'; '.join(said)} (takes {', '.join(wanted) or 'nothing'})")
    typed = tool.read(args)
    if isinstance(typed, InvalidCall):
        return InvalidCall(f"{name}: {typed.reason}")
    return tool, typed

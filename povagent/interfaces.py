"""The base classes a plugin implements: backends, strategies, parsers, scorers.

A plugin registers a *factory* (usually one of these subclasses) under a name through the
``register_*`` hooks in :mod:`povagent.hookspecs`; the runner calls ``factory(**options)`` with
the options from the pipeline YAML. Everything here is abstract: no file, network or clock.
"""

from __future__ import annotations

import abc
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Awaitable, Callable, ClassVar, Literal, Mapping, Protocol

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.exchange.messages import Request, Response

if TYPE_CHECKING:
    from povagent.active.tools import ToolSet
    from povagent.dataset.instances import Instance
    from povagent.dataset.set_interface import EvaluationSet
    from povagent.exchange.images import ImageStore
    from povagent.scoring.metrics import Metric
    from povagent.scoring.normalized_l2 import OfficialScore

#: What a multi-turn strategy calls to talk to the model: cached, retried, rate-limited.
Ask = Callable[[Request], Awaitable[Response]]

#: How :func:`earlier_answer` writes a placeholder (``what`` empty: the whole answer).
_PLACEHOLDER = re.compile(r"<<(?:(?P<what>[^<>]*?), read from )?the model's answer to turn (?P<turn>[1-9][0-9]*)>>")


def earlier_answer(turn: int, what: str = "") -> str:
    """The placeholder a planned turn shows where the model's earlier answer will stand.

    ``earlier_answer(1)`` stands for the whole answer to turn 1 (``<<the model's answer to turn
    1>>``); ``earlier_answer(1, "anchor")`` for a value read from it (``<<anchor, read from the
    model's answer to turn 1>>``). Dry runs count a whole-answer placeholder as that turn's
    ``max_tokens``.
    """
    if not isinstance(turn, int) or turn < 1:
        raise ValueError(f"earlier_answer: turn must be a positive integer, got {turn!r}")
    return f"<<{what}, read from the model's answer to turn {turn}>>" if what else f"<<the model's answer to turn {turn}>>"


def whole_answer_placeholders(text: str) -> list[int]:
    """The turns whose whole answer ``text`` holds a placeholder for (:func:`earlier_answer`
    without ``what``), in order."""
    return [int(m.group("turn")) for m in _PLACEHOLDER.finditer(text) if m.group("what") is None]


@dataclass(frozen=True)
class PlannedTurn:
    """One turn a strategy will take for an instance, known before any model call.

    ``request`` is the request as it will be sent, with :func:`earlier_answer` placeholders
    where it carries the model's earlier answers (or values read from them). ``sent`` is
    ``False`` for a turn the strategy works out itself (``Response.by_strategy``), never sent.
    ``note`` says when the turn is taken if not always (``"asked when turn 1 names an anchor"``).
    """

    request: Request
    sent: bool = True
    note: str = ""


class TransientBackendError(Exception):
    """A failure worth retrying: timeout, dropped connection, 429, 5xx, an empty answer.

    ``retry_after`` (seconds) is honoured when the server sent one. ``kind`` optionally names
    the failure for the row's ``error_type`` (``"connection"``, ``"timeout"``,
    ``"empty_response"``); without it the kind follows ``status``.
    """

    def __init__(
        self, message: str, *, retry_after: float | None = None, status: int | None = None, kind: str | None = None
    ) -> None:
        super().__init__(message)
        self.retry_after = retry_after
        self.status = status
        self.kind = kind


class PermanentBackendError(Exception):
    """A failure not worth retrying: bad request, authentication, unknown model (4xx), a
    missing API key. ``kind`` optionally names it (``"missing_key"``)."""

    def __init__(self, message: str, *, status: int | None = None, kind: str | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.kind = kind


class Backend(abc.ABC):
    """A model (or an offline baseline) that answers requests.

    Subclasses take their YAML options as keyword arguments. ``identity()`` must describe
    everything that changes answers (it is part of the cache key) and nothing secret.
    """

    #: Whether answers may be cached (offline baselines that are instant can say False).
    cacheable: ClassVar[bool] = True
    #: Whether this backend is an offline baseline, not a model: it answers from the records or
    #: by a fixed rule (the centre, a random pixel, the ground truth, an explorer walking to it).
    #: Reports show its runs as reference rows, styled and sorted as baselines and never marked
    #: best; the report reads this from the backend's class, never from its name.
    offline_baseline: ClassVar[bool] = False
    #: Whether :meth:`complete` answers in this process without waiting on anything (no network,
    #: no other process or thread, no ``await`` that suspends): the offline baselines and test
    #: backends. The runner then answers such a backend's keys a chunk at a time, in order, with
    #: no task, concurrency slot, timeout or thread hand-off per request (none of them can act
    #: on a call that never suspends); retries, the response cache and the rows stay the same.
    answers_in_process: ClassVar[bool] = False

    @abc.abstractmethod
    def identity(self) -> Mapping[str, Any]:
        """JSON-able identity: model name and answer-changing options; never API keys."""

    @abc.abstractmethod
    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer one request. Raise TransientBackendError / PermanentBackendError on failure."""

    async def start(self) -> None:  # noqa: B027 - optional hook
        """Get ready before the first request (import a client library, open a pool).

        Called once by the runner (when its first request misses the response cache) and
        by the agent, before any request's timeout starts, so a slow import never counts
        against the first requests' time. The default does nothing.
        """

    def preload(self) -> None:  # noqa: B027 - optional hook
        """Start loading client libraries in the background and return at once.

        The runner calls it at its very start when a request will surely be sent (no row in
        the run folder yet, no response cache to answer from), so a slow import overlaps the
        loading of the dataset; :meth:`start` still follows, and must wait for what this
        began. The default does nothing.
        """

    async def aclose(self) -> None:  # noqa: B027 - optional hook
        """Release connections; called once when the run ends."""

    def check_image_transport(self, transport: str) -> None:  # noqa: B027 - optional hook
        """Raise :class:`povagent.errors.ConfigError` if this backend cannot send images by
        ``transport`` (``"inline"``, ``"file"`` or ``"http"``, see
        :mod:`povagent.exchange.transport`); called before a run starts. The default accepts
        all: a backend that sends images takes their URLs from ``ImageStore.url``, which follows
        the transport, and one that sends none (an offline baseline) is not concerned.
        """


class LoadedPlugins(Protocol):
    """What a strategy may ask of the plugins a run loaded (:class:`povagent.plugins.PluginHost`)."""

    def tools(self, task: str | None = "point") -> ToolSet:
        """The registered active-mode tools an episode of ``task`` offers (``None``: every
        registered tool), in the order offered."""
        ...


class Strategy(abc.ABC):
    """How a model is asked: prompt text, images (perhaps marked) and the answer format."""

    #: The parser this strategy's answers need, when only one reads them (the ``active``
    #: strategy's episode record: ``"active"``); ``None``: any parser of its answer type. A
    #: pipeline naming no parser gets this one; one naming another is refused at load.
    answer_parser: ClassVar[str | None] = None
    #: The answer type this strategy asks for; a parser that does not read it is refused at load.
    answer_type: ClassVar[str] = "point"
    #: The parser a pipeline naming none gets, when any parser of :attr:`answer_type` may read
    #: the answers (the ``choice`` strategy's: ``"choice"``); ``None``: the usual default.
    default_parser: ClassVar[str | None] = None

    @abc.abstractmethod
    def build(self, instance: Instance, images: ImageStore) -> Request:
        """The (first) request for an instance."""

    def answer_spec(self, instance: Instance) -> AnswerSpec | None:
        """What the strategy asks ``instance`` to answer, without building a request.

        Used to re-parse finished runs offline (``povagent rescore``). Returning ``None``
        (the default) makes callers build the full request instead, which reads the images.
        """
        return None

    async def solve(self, instance: Instance, ask: Ask, images: ImageStore) -> list[tuple[Request, Response]]:
        """Talk to the model and return every exchange, the final answer last.

        The default is single-turn: build one request and ask once. Multi-turn strategies
        (self-checking, tool use) override this and may call ``ask`` several times; they
        override :meth:`plan_turns` too, so the turns are known before the run.
        """
        request = self.build(instance, images)
        return [(request, await ask(request))]

    def use_run_folder(self, folder: Path) -> None:  # noqa: B027 - optional hook
        """Where this run's files are: called once by the runner before the first instance, so a
        strategy that makes files of its own (the active mode's rendered views) keeps them there
        and a resumed run finds them. The default does nothing."""

    def use_plugins(self, host: LoadedPlugins) -> None:  # noqa: B027 - optional hook
        """The plugins loaded where the strategy is made: the plugin host calls it once, as it
        makes the strategy, so a strategy that offers registered things (the active mode's
        tools) offers those of the run's plugins. The default does nothing."""

    def identity(self) -> Mapping[str, Any]:
        """What, beyond the pipeline's YAML, decides the rows this strategy makes (the active
        mode: the tools it offers), recorded in the config hash so rows made otherwise never
        mix. The default is empty, which leaves the hash the YAML's alone."""
        return {}

    def plan_turns(self, instance: Instance, images: ImageStore) -> list[PlannedTurn]:
        """Every turn :meth:`solve` takes for ``instance``, in order, without calling a model.

        ``povagent show-prompt`` prints each planned request and ``sweep --dry-run`` counts
        requests and tokens per turn from them. A later turn's request holds
        :func:`earlier_answer` placeholders where the model's earlier answers will stand. A turn
        taken only sometimes is listed with a ``note`` saying when (dry runs count it: an upper
        bound). The default is :meth:`build`'s one request; a strategy that overrides
        :meth:`solve` without this method is reported as having undeclared later turns
        (:func:`declares_turns`).
        """
        return [PlannedTurn(self.build(instance, images))]


def declares_turns(strategy: Strategy) -> bool:
    """Whether ``strategy``'s :meth:`Strategy.plan_turns` describes every turn its
    :meth:`Strategy.solve` takes: true unless ``solve`` is overridden and ``plan_turns`` is not."""
    cls = type(strategy)
    return cls.solve is Strategy.solve or cls.plan_turns is not Strategy.plan_turns


class Parser(abc.ABC):
    """Reads an answer (a point, and a frame) out of a model's raw text. Must never raise on bad text."""

    #: The answer types this parser reads (see :attr:`Strategy.answer_type`).
    answer_types: ClassVar[frozenset[str]] = frozenset({"point"})

    @abc.abstractmethod
    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """A typed parse of ``text`` given what was asked (``spec``)."""


#: The scoring protocols the core breaks down beyond declared metrics, each a fixed set of score
#: fields. ``normalized_l2``: POVBench's error (``answered``, ``l2``, ``l2_strict``,
#: ``gt_in_frame``, ``gt_behind``, ``gt_u``, ``gt_v``), the top-level breakdown of
#: ``summary.json``, the report's error tables, centre baseline and paired comparisons.
#: ``marked_hit``: a hit against hand-marked ground truth (``answered``, ``success``,
#: ``frame_has_gt``, ``distance_norm``, ``hit_radius_px``), the ``success`` section of
#: ``summary.json`` and the report's success-rate tables.
ScoreProtocol = Literal["normalized_l2", "marked_hit"]
#: The diagnoses a scorer's fields may carry for the summary's ``diagnostics`` section (an
#: addition beside the official breakdown): ``failure_step``, the step of the chain an answer
#: failed at (with ``step``, ``nearer_egocentric``, ``egocentric``, ``mirrored``), and
#: ``relation_hit``, whether the answer satisfies the sentence's relation (``success``).
Diagnosis = Literal["failure_step", "relation_hit"]


class Scorer(abc.ABC):
    """Scores one parsed answer against the ground truth."""

    #: The numbers this scorer's fields give (:class:`~povagent.scoring.metrics.Metric`):
    #: ``summary.json``'s ``metrics`` section, the console and the report show each, per slice.
    metrics: ClassVar[tuple[Metric, ...]] = ()
    #: The protocol this scorer's fields follow, when the summary and the report break it down in
    #: sections of their own (:data:`ScoreProtocol`); ``None``, the usual case, when its declared
    #: metrics say all there is to show.
    protocol: ClassVar[ScoreProtocol | None] = None
    #: The diagnosis this scorer's fields carry (:data:`Diagnosis`), which the summary's and the
    #: report's diagnostics read from it; ``None``, the usual case, for none.
    diagnosis: ClassVar[Diagnosis | None] = None
    #: Whether it projects the instance's 3D target (a real-world set, marked by hand in 2D,
    #: refuses such a scorer before any request).
    needs_3d_target: ClassVar[bool] = False
    #: The declared metric a leaderboard shows as the set's number (the report's systems x sets
    #: table); ``None``: the first of :attr:`metrics`.
    headline: ClassVar[str | None] = None

    @abc.abstractmethod
    def score(self, instance: Instance, answer: ParsedAnswer, dataset: EvaluationSet | None) -> dict[str, Any]:
        """JSON-able scores for one row (e.g. ``{"answered": True, "l2": 0.12, ...}``)."""

    def point_fields(self, point: OfficialScore, l2_closest: float | None = None) -> dict[str, Any]:
        """A ``normalized_l2`` scorer's row fields for a point the protocol placed already
        (``point``: its official score in the scored frame; ``l2_closest``: a multi-point
        answer's closest point's error). ``povagent score`` scores prediction files that hold
        no parsed answer through it, so its fields and the metrics declared over them are a
        run's; a scorer following no point protocol never has it asked."""
        raise NotImplementedError(f"{type(self).__name__} scores no point placed by the normalized_l2 protocol")

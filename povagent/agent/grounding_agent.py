"""The embeddable GroundingAgent: a robot's frames and a user's sentence in, a goal out.

A robot team has frames from its own robot (any size, as files, PIL images or numpy arrays)
and a sentence from a user ("while I was cooking I left my phone to the right of the kettle").
:class:`GroundingAgent` asks a model which frame shows the target and where, using the same
backends, strategies and parsers as a benchmark run, and returns a typed :class:`Localization`:
the frame, the pixel in the *original* frame, the normalized point, how the answer parsed, the
raw answer, latency and tokens, and, when the frame's camera is given, a 3D goal in the robot's
world frame (on the floor, or at a depth image's depth; see :mod:`povagent.geometry.goals`).

How one call goes, one room each: the inputs are checked (:mod:`~povagent.agent.frame_inputs`);
frames are letterboxed to the benchmark's 512x512 into a fresh image store and a synthetic
:class:`~povagent.dataset.instances.Instance` is built around them (condition A when frames are
given, C when an ``observer_view`` is; :mod:`~povagent.agent.prepared_call`); the strategy
talks to the backend through an ``ask`` function that retries transient failures within a
deadline (:mod:`~povagent.agent.ask_factory`); the parser reads the final answer, and the pixel
is mapped back through the exact letterbox transform and, with a camera, back-projected
(:mod:`~povagent.agent.localization`). A strategy that solves the geometry itself
(:class:`~povagent.agent.solver_cameras.PosedSolver`: ``geometric``) is given the robot's
cameras, brought into the benchmark's world, and its 3D target is mapped back into the robot's
(:mod:`~povagent.agent.solver_cameras`). This module holds the agent itself: building it,
its event loop and its timeout, and the order of those steps.

What a robot app can catch (all :class:`~povagent.errors.GroundingError`):
:class:`~povagent.errors.BadInputError` (no frames, an unreadable image, cameras or depth
images that do not match the frames), :class:`~povagent.errors.NoAnswerError` (every attempt
failed, or no answer within ``timeout_s``: a call never outlives its timeout) and
:class:`~povagent.errors.UnparseableAnswerError` (the model answered but named no usable point
or frame; the raw answer is on the exception). A 3D goal that cannot be computed (a pixel above
the horizon, a hole in the depth image) is not an error: ``goal`` is ``None`` and ``goal_error``
says why, since the pixel is still useful.

This module must not read datasets, write result rows or score: it embeds, it does not evaluate.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import os
import threading
import time
from typing import Any, Literal, Mapping, Sequence

import numpy as np

from povagent.agent.ask_factory import AGENT_RETRY, AskFactory, default_ask_factory
from povagent.agent.frame_inputs import FrameInput
from povagent.agent.frame_memory import FrameMemory
from povagent.agent.localization import Localization, localize
from povagent.agent.prepared_call import PreparedCall, prepare_call
from povagent.agent.shown_frame import ShownFrame
from povagent.agent.solver_cameras import PosedSolver
from povagent.config.retry_policy import RetryPolicy
from povagent.errors import BackendError, NoAnswerError
from povagent.exchange.messages import Request, Response
from povagent.geometry.goals import FLOOR, GoalCamera, Plane
from povagent.geometry.letterbox import DEFAULT_PAD_COLOR
from povagent.interfaces import Backend, Parser, PermanentBackendError, Strategy, TransientBackendError
from povagent.results.official_reading import OFFICIAL_PARSER

#: Default wall-clock budget of one ``locate`` call (seconds), every attempt included.
DEFAULT_TIMEOUT_S = 120.0


# -- the agent ------------------------------------------------------------------------------------
class GroundingAgent:
    """Locate a sentence's target in a robot's frames with any povagent pipeline.

    Build it from keyword arguments (plugin names with options, or ready objects) or from a
    pipeline YAML with :meth:`from_pipeline`. ``model=`` is the short form of the litellm
    backend, as ``model:`` is in a pipeline: a model profile (``"gpt-5.4"``, whose default
    parser then applies) or any litellm model string; ``backend_options`` add to it (e.g.
    ``api_base`` for a vLLM server). Without a model or backend the agent runs the offline
    ``center`` baseline. ``timeout_s`` bounds each call, every retry
    included. ``plane`` is the floor (normal pointing up) a pixel is back-projected onto when
    no depth image is given, and the floor the ``geometric`` solver stands objects on (default:
    AI2-THOR's ``y = 0``; a ROS robot passes ``Plane.horizontal(0.0, up_axis="z")``).
    ``trust_remote_code=True`` lets a checkpoint's own Python code run (the ``transformers``
    backend): only this call grants it, never a pipeline's options (see
    :mod:`povagent.config.remote_code`).
    The agent holds a backend (with its connections): use it as a context manager, or call
    :meth:`close` / :meth:`aclose`.
    """

    def __init__(
        self,
        backend: str | Backend | None = None,
        *,
        model: str | None = None,
        strategy: str | Strategy = "basic",
        parser: str | Parser | None = None,
        backend_options: Mapping[str, Any] | None = None,
        strategy_options: Mapping[str, Any] | None = None,
        parser_options: Mapping[str, Any] | None = None,
        plugins: Sequence[str] = (),
        timeout_s: float = DEFAULT_TIMEOUT_S,
        retry: RetryPolicy | None = None,
        attempt_timeout_s: float | None = None,
        plane: Plane = FLOOR,
        depth_kind: Literal["z", "range"] = "z",
        pad_color: tuple[int, int, int] = DEFAULT_PAD_COLOR,
        ask_factory: AskFactory | None = None,
        trust_remote_code: bool = False,
    ) -> None:
        if timeout_s <= 0:
            raise ValueError(f"timeout_s must be positive, got {timeout_s}")
        if model is not None:
            if backend not in (None, "litellm"):
                raise ValueError(f"give model= (a litellm model or profile) or backend=, not both (got backend={backend!r})")
            if backend_options and backend_options.get("model") not in (None, model):
                raise ValueError(f"model={model!r} and backend_options['model']={backend_options['model']!r} disagree")
            backend, backend_options = "litellm", {**(backend_options or {}), "model": model}
        elif backend is None:
            backend = "center"
        host = None
        if isinstance(backend, str) or isinstance(strategy, str) or not isinstance(parser, Parser):
            from povagent.plugins import get_plugin_host

            host = get_plugin_host(tuple(plugins))
        if isinstance(backend, Backend):
            self.backend: Backend = backend
        else:
            assert host is not None  # a name, so the host was built above
            from povagent.config.remote_code import remote_code_granted

            with remote_code_granted(trust_remote_code):
                self.backend = host.backend(backend, backend_options)
        if isinstance(strategy, Strategy):
            self.strategy: Strategy = strategy
        else:
            assert host is not None
            self.strategy = host.strategy(strategy, strategy_options)
        if parser is None:
            # a model profile knows how its family writes points (Qwen 0-1000, Gemini [y, x] ...)
            profile = getattr(self.backend, "profile", None)
            parser = getattr(profile, "default_parser", None) or OFFICIAL_PARSER
        if isinstance(parser, Parser):
            self.parser: Parser = parser
        else:
            assert host is not None
            self.parser = host.parser(parser, parser_options)
        self.timeout_s = float(timeout_s)
        self.retry = retry or AGENT_RETRY
        self.plane = plane
        self.depth_kind = depth_kind
        self.pad_color = pad_color
        self._ask_factory = ask_factory or default_ask_factory(self.retry, attempt_timeout_s)
        self._started = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._loop_thread: threading.Thread | None = None
        self._lock = threading.Lock()
        #: frames handed in bare, by content: the same arrays or files again cost a digest each
        self._frames = FrameMemory()

    @classmethod
    def from_pipeline(cls, pipeline: str | os.PathLike | Mapping[str, Any], **overrides: Any) -> GroundingAgent:
        """An agent from a pipeline YAML (a path or an already-parsed mapping).

        The same file a benchmark run takes works here: ``plugins``, ``model`` or ``backend``,
        ``strategy``, ``parser``, ``retry`` and ``timeout`` are used; ``dataset``, ``output``
        and the rest are ignored (and may be left out). Keyword ``overrides`` go to
        :class:`GroundingAgent` (e.g. ``plane=``). Problems are :class:`~povagent.errors.ConfigError`
        naming the file and line.
        """
        from povagent.config.pipeline import pipeline_from_source
        from povagent.config.yaml_reader import ConfigSource, read_yaml

        if isinstance(pipeline, Mapping):
            source = ConfigSource("<pipeline mapping>", dict(pipeline), {})
        else:
            source = read_yaml(pipeline)
        data = source.data
        if isinstance(data, Mapping):
            # the agent needs no dataset or output folder: placeholders satisfy the run schema
            data = {"dataset": {"path": "."}, "output": ".", **dict(data)}
        config = pipeline_from_source(ConfigSource(source.file, data, source.lines))
        assert config.backend is not None and config.parser is not None  # resolved above
        kwargs: dict[str, Any] = dict(
            backend=config.backend.name,
            backend_options=config.backend.options,
            strategy=config.strategy.name,
            strategy_options=config.strategy.options,
            parser=config.parser.name,
            parser_options=config.parser.options,
            plugins=tuple(config.plugins),
            timeout_s=config.timeout,
            retry=config.retry,
        )
        kwargs.update(overrides)
        return cls(**kwargs)

    # -- public API ---------------------------------------------------------------------------
    def locate(
        self,
        sentence: str,
        frames: Sequence[FrameInput | ShownFrame] = (),
        *,
        observer_view: FrameInput | ShownFrame | None = None,
        cameras: Sequence[GoalCamera | None] | GoalCamera | None = None,
        depths: Sequence[np.ndarray | None] | np.ndarray | None = None,
        timeout_s: float | None = None,
    ) -> Localization:
        """Blocking :meth:`alocate` (runs on the agent's own event-loop thread).

        Safe to call from any thread, including one already running an event loop.
        """
        budget = self.timeout_s if timeout_s is None else float(timeout_s)
        future = asyncio.run_coroutine_threadsafe(
            self.alocate(sentence, frames, observer_view=observer_view, cameras=cameras, depths=depths, timeout_s=budget),
            self._ensure_loop(),
        )
        try:
            # alocate enforces the budget itself; this wait is a backstop a little longer
            return future.result(timeout=budget + 2.0)
        except concurrent.futures.TimeoutError:
            future.cancel()
            raise NoAnswerError(f"no answer within {budget:g} s") from None

    async def alocate(
        self,
        sentence: str,
        frames: Sequence[FrameInput | ShownFrame] = (),
        *,
        observer_view: FrameInput | ShownFrame | None = None,
        cameras: Sequence[GoalCamera | None] | GoalCamera | None = None,
        depths: Sequence[np.ndarray | None] | np.ndarray | None = None,
        timeout_s: float | None = None,
    ) -> Localization:
        """Locate the target of ``sentence`` in ``frames`` (or in ``observer_view``).

        ``frames``: the robot's exploration frames (conditions A/B); a frame asked about again
        and again keeps its name, letterbox and encoding from one call to the next, whether it
        is handed in as a :class:`~povagent.agent.shown_frame.ShownFrame` or again as the same
        array, image or file (the agent knows it by a digest of its content). ``observer_view``: one
        frame from the speaker's viewpoint (condition C; ``frames`` are then not shown).
        ``cameras`` and ``depths`` line up with the images shown (``frames``, or the one
        observer view; ``None`` entries allowed): a camera (:class:`~povagent.geometry.camera.Camera`
        or :class:`~povagent.geometry.goals.PinholeCamera`, describing the original frame's size) makes a
        3D goal; a depth image (metres) makes it the measured point instead of the floor's.
        """
        budget = self.timeout_s if timeout_s is None else float(timeout_s)
        started = time.monotonic()
        deadline = started + budget
        try:
            async with asyncio.timeout(budget):
                if not self._started:
                    # the backend's client library loads once (litellm: seconds), inside the
                    # budget: a locate call never outlives its timeout
                    try:
                        await self.backend.start()
                    except (TransientBackendError, PermanentBackendError) as exc:
                        raise NoAnswerError(f"the backend cannot start: {exc}") from exc
                    self._started = True
                prepared = await asyncio.to_thread(
                    prepare_call, sentence, frames, observer_view, cameras, depths,
                    pad_color=self.pad_color, plane=self.plane, posed=isinstance(self.strategy, PosedSolver),
                    memory=self._frames,
                )
                exchanges = await self._solve(prepared, deadline)
        except TimeoutError:
            raise NoAnswerError(f"no answer within {budget:g} s (the agent's timeout_s)") from None
        return localize(prepared, exchanges, time.monotonic() - started, self.parser, self.plane, self.depth_kind)

    def close(self) -> None:
        """Release the backend's connections and stop the agent's loop thread."""
        with self._lock:
            loop, thread = self._loop, self._loop_thread
            self._loop, self._loop_thread = None, None
        if loop is None:
            return
        try:
            asyncio.run_coroutine_threadsafe(self.backend.aclose(), loop).result(timeout=10)
            # client libraries leave background tasks on the loop (litellm's logging worker):
            # end them here, or they complain when the closed loop is collected
            asyncio.run_coroutine_threadsafe(_cancel_other_tasks(), loop).result(timeout=10)
        finally:
            loop.call_soon_threadsafe(loop.stop)
            if thread is not None:
                thread.join(timeout=10)
            loop.close()

    async def aclose(self) -> None:
        """Release the backend's connections (for agents used through :meth:`alocate`)."""
        await self.backend.aclose()
        self.close()

    def __enter__(self) -> GroundingAgent:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    async def __aenter__(self) -> GroundingAgent:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    # -- steps --------------------------------------------------------------------------------
    def _ensure_loop(self) -> asyncio.AbstractEventLoop:
        # One long-lived loop: backends may hold connections bound to the loop they opened on.
        with self._lock:
            if self._loop is None:
                loop = asyncio.new_event_loop()
                thread = threading.Thread(target=loop.run_forever, name="povagent-agent-loop", daemon=True)
                thread.start()
                self._loop, self._loop_thread = loop, thread
            return self._loop

    async def _solve(self, prepared: PreparedCall, deadline: float) -> list[tuple[Request, Response]]:
        ask = self._ask_factory(self.backend, prepared.images, deadline)
        try:
            if prepared.solver_cameras is not None and isinstance(self.strategy, PosedSolver):
                exchanges = await self.strategy.solve_posed(prepared.instance, ask, prepared.images, prepared.solver_cameras)
            else:
                exchanges = await self.strategy.solve(prepared.instance, ask, prepared.images)
        except (TransientBackendError, PermanentBackendError, BackendError) as exc:
            raise NoAnswerError(f"the model gave no answer: {type(exc).__name__}: {exc}") from exc
        if not exchanges:
            raise NoAnswerError("the strategy made no request to the model")
        return list(exchanges)


async def _cancel_other_tasks() -> None:
    """Cancel every task on the running loop but this one, and wait for them to end."""
    me = asyncio.current_task()
    others = [t for t in asyncio.all_tasks() if t is not me]
    for t in others:
        t.cancel()
    await asyncio.gather(*others, return_exceptions=True)
    await asyncio.get_running_loop().shutdown_asyncgens()


__all__ = ["DEFAULT_TIMEOUT_S", "GroundingAgent"]

"""The embeddable GroundingAgent: a robot's frames and a user's sentence in, a goal out.

A robot team has frames from its own robot (any size, as files, PIL images or numpy arrays)
and a sentence from a user ("while I was cooking I left my phone to the right of the kettle").
:class:`GroundingAgent` asks a model which frame shows the target and where, using the same
backends, strategies and parsers as a benchmark run, and returns a typed :class:`Localization`:
the frame, the pixel in the *original* frame, the normalized point, how the answer parsed, the
raw answer, latency and tokens, and, when the frame's camera is given, a 3D goal in the robot's
world frame (on the floor, or at a depth image's depth; see :mod:`povagent.geometry.goals`).

How one call goes: frames are letterboxed to the benchmark's 512x512 (:mod:`povagent.geometry.letterbox`,
as the paper does for house-tour videos) and put into a fresh image store; a synthetic
:class:`~povagent.dataset.instances.Instance` is built (condition A when frames are given, C when
an ``observer_view`` is); the strategy talks to the backend through an ``ask`` function that
retries transient failures within a deadline; the parser reads the final answer; the pixel is
mapped back through the exact letterbox transform and, with a camera, back-projected.

A strategy that solves the geometry itself (:class:`PosedSolver`: ``geometric``) is given the
robot's cameras instead of being told nothing about them: each camera (AI2-THOR's ``Camera`` or
a ``PinholeCamera`` in any convention, any intrinsics and frame size) is brought into the
benchmark's world (:class:`~povagent.geometry.solver_world.SolverWorld`: y up, the floor plane
``plane`` at ``y = 0``) and onto the letterboxed square the model sees
(:meth:`~povagent.geometry.goals.PinholeCamera.letterboxed`); the 3D target it solves is mapped
back into the robot's world and returned as the goal.

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
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Literal, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np
from PIL import Image, UnidentifiedImageError
from pydantic import BaseModel, ConfigDict

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.config.retry_policy import RetryPolicy
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.models import Condition, Direction
from povagent.dataset.realworld import unknown_object, unposed_square_camera
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import InfraFailure, is_transient
from povagent.errors import BackendError, BadInputError, NoAnswerError, UnparseableAnswerError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.geometry.camera import Camera, ViewCamera
from povagent.geometry.goals import FLOOR, Goal3D, GoalCamera, GoalUnavailable, PinholeCamera, Plane, back_project, camera_problem
from povagent.geometry.letterbox import DEFAULT_PAD_COLOR, Letterbox, pixel_index
from povagent.geometry.solver_world import SolverWorld
from povagent.interfaces import Ask, Backend, Parser, PermanentBackendError, Strategy, TransientBackendError

#: What a frame may be: a path, a PIL image, or an ``(H, W)``/``(H, W, 3|4)`` RGB(A) array.
FrameInput = str | os.PathLike | Image.Image | np.ndarray

#: Default wall-clock budget of one ``locate`` call (seconds), every attempt included.
DEFAULT_TIMEOUT_S = 120.0

#: The id parts of the synthetic instance (the prompts never show them).
AGENT_HOUSE_ID = "agent"
AGENT_PAIR_ID = "query"


class Localization(BaseModel):
    """Where the model put the target, in the robot's own frame (and world, given a camera).

    ``frame_index`` is the index of the chosen frame in ``frames`` (A/B), or 0 for the observer
    view (C). ``pixel`` is a continuous coordinate in that original frame (``(0, 0)`` its
    top-left corner, ``(W, H)`` its bottom-right; see :mod:`povagent.geometry.letterbox`) and
    ``pixel_index`` the ``(column, row)`` of the pixel containing it; ``normalized`` is
    ``pixel / (W, H)``. ``square_point`` is the answer as the model gave it in the letterboxed
    512x512 image, and ``on_padding`` says it fell on the letterbox border (it was moved to the
    nearest image edge). ``latency_s`` is the whole call's wall time; ``model_latency_s`` the
    sum of the model calls'. ``goal`` is the 3D point when a camera was given for the frame.
    """

    model_config = ConfigDict(frozen=True)

    condition: Condition
    frame_index: int
    pixel: tuple[float, float]
    pixel_index: tuple[int, int]
    normalized: tuple[float, float]
    frame_size: tuple[int, int]
    square_point: tuple[float, float]
    on_padding: bool
    status: ParseStatus
    reason: str = ""
    repair: str | None = None
    raw_answer: str
    latency_s: float
    model_latency_s: float
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cost_usd: float | None = None
    retries: int = 0
    exchanges: int = 1
    goal: Goal3D | None = None
    goal_error: str | None = None

    @property
    def point_3d(self) -> tuple[float, float, float] | None:
        """The 3D goal's coordinates, or ``None`` when none was computed."""
        return self.goal.point if self.goal is not None else None


# -- the ask seam ---------------------------------------------------------------------------------
#: Builds the ``ask`` a strategy calls, given the backend, the call's image store and the
#: monotonic deadline of the whole call. The default sends through the engine's one request
#: path (:class:`~povagent.engine.request_path.RequestPath`), as the runner does; a robot app
#: may pass its own (``ask_factory=``) to add logging or a cache.
AskFactory = Callable[[Backend, ImageStore, float], Ask]

#: The agent's retry defaults: a robot waits for its answer, so fewer, shorter waits than a run.
AGENT_RETRY = RetryPolicy(attempts=3, initial_wait=0.5, max_wait=8.0)


def default_ask_factory(retry: RetryPolicy, attempt_timeout_s: float | None = None) -> AskFactory:
    """An ``ask`` that sends through :class:`~povagent.engine.request_path.RequestPath`.

    Failures are classified, retried and timed exactly as in a run (timeouts, dropped
    connections, 429 and 5xx are retried; a server's Retry-After is honoured, capped; backoff
    has jitter); every attempt and wait is also cut at the call's deadline. A request that gets
    no answer becomes :class:`NoAnswerError`, its cause chained. ``attempt_timeout_s`` bounds
    one attempt (default: the time left before the deadline).
    """

    def factory(backend: Backend, images: ImageStore, deadline: float) -> Ask:
        timeout = attempt_timeout_s if attempt_timeout_s is not None else max(0.001, deadline - time.monotonic())
        path = RequestPath(backend, images, policy=retry, timeout_s=timeout)

        async def ask(request: Request) -> Response:
            try:
                return await path.send(request, label="agent", deadline=deadline)
            except InfraFailure as exc:
                if exc.error_type == "backend_exception":
                    raise NoAnswerError(f"the backend failed (a bug in it, not the model): {exc.message}") from exc.__cause__
                if not is_transient(exc.__cause__ or exc):
                    raise NoAnswerError(f"the model refused the request ({exc.error_type}): {exc.message}") from exc
                raise NoAnswerError(
                    f"no answer after {exc.attempts} attempt(s) within the deadline; last error ({exc.error_type}): {exc.message}"
                ) from exc

        return ask

    return factory


# -- inputs ---------------------------------------------------------------------------------------
def load_frame(frame: FrameInput, what: str) -> Image.Image:
    """A frame as an RGB PIL image; :class:`BadInputError` naming ``what`` when unusable.

    Arrays are taken as RGB (OpenCV's BGR arrays must be converted first): ``uint8``, or floats
    on ``[0, 1]``; 2D arrays are grey, a 4th channel (alpha) is dropped.
    """
    if isinstance(frame, Image.Image):
        return frame.convert("RGB")
    if isinstance(frame, np.ndarray):
        return _array_to_image(frame, what)
    if isinstance(frame, (str, os.PathLike)):
        path = Path(frame)
        try:
            with Image.open(path) as im:
                im.load()
                return im.convert("RGB")
        except FileNotFoundError:
            raise BadInputError(f"{what}: no such image file: {path}") from None
        except (UnidentifiedImageError, Image.DecompressionBombError, OSError, ValueError) as exc:
            raise BadInputError(f"{what}: cannot read image {path}: {exc}") from None
    raise BadInputError(f"{what}: expected a path, a PIL image or a numpy array, got {type(frame).__name__}")


def _array_to_image(a: np.ndarray, what: str) -> Image.Image:
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise BadInputError(f"{what}: an image array must be (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}")
    if a.shape[0] < 1 or a.shape[1] < 1:
        raise BadInputError(f"{what}: empty image array of shape {a.shape}")
    if a.dtype == np.uint8:
        data = a
    elif a.dtype == np.bool_:
        data = a.astype(np.uint8) * 255
    elif np.issubdtype(a.dtype, np.floating):
        if not np.isfinite(a).all() or a.min() < 0 or a.max() > 1:
            raise BadInputError(f"{what}: a float image array must hold values in [0, 1]")
        data = np.round(a * 255).astype(np.uint8)
    else:
        raise BadInputError(f"{what}: image arrays must be uint8 or float in [0, 1], got dtype {a.dtype}")
    if data.ndim == 3 and data.shape[2] == 4:
        data = data[..., :3]
    return Image.fromarray(np.ascontiguousarray(data)).convert("RGB")


@runtime_checkable
class PosedSolver(Protocol):
    """A strategy that solves the geometry with the shown frames' cameras (``geometric``).

    ``solve_posed`` is :meth:`~povagent.interfaces.Strategy.solve` with one camera per shown
    image, describing that (letterboxed, square) image in the benchmark's world: y up, the floor
    at ``y = 0``, left-handed. A 3D target it works out (``Response.solved_point``) is in that
    world; the agent maps it back into the robot's.
    """

    async def solve_posed(
        self, instance: Instance, ask: Ask, images: ImageStore, cameras: Sequence[ViewCamera]
    ) -> list[tuple[Request, Response]]:
        """Every exchange, the final answer last."""
        ...


@dataclass
class _Prepared:
    """One call's inputs, ready for the strategy (``solver_cameras`` and ``world`` only for a
    :class:`PosedSolver`)."""

    instance: Instance
    images: ImageStore
    boxes: list[Letterbox]
    cameras: list[GoalCamera | None]
    depths: list[np.ndarray | None]
    folder: tempfile.TemporaryDirectory
    solver_cameras: list[ViewCamera] | None = None
    world: SolverWorld | None = None


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
            self.backend = host.create("backend", backend, backend_options)
        if isinstance(strategy, Strategy):
            self.strategy: Strategy = strategy
        else:
            assert host is not None
            self.strategy = host.create("strategy", strategy, strategy_options)
        if parser is None:
            # a model profile knows how its family writes points (Qwen 0-1000, Gemini [y, x] ...)
            profile = getattr(self.backend, "profile", None)
            parser = getattr(profile, "default_parser", None) or "json"
        if isinstance(parser, Parser):
            self.parser: Parser = parser
        else:
            assert host is not None
            self.parser = host.create("parser", parser, parser_options)
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
        frames: Sequence[FrameInput] = (),
        *,
        observer_view: FrameInput | None = None,
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
        frames: Sequence[FrameInput] = (),
        *,
        observer_view: FrameInput | None = None,
        cameras: Sequence[GoalCamera | None] | GoalCamera | None = None,
        depths: Sequence[np.ndarray | None] | np.ndarray | None = None,
        timeout_s: float | None = None,
    ) -> Localization:
        """Locate the target of ``sentence`` in ``frames`` (or in ``observer_view``).

        ``frames``: the robot's exploration frames (conditions A/B). ``observer_view``: one
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
                prepared = await asyncio.to_thread(self._prepare, sentence, frames, observer_view, cameras, depths)
                try:
                    exchanges = await self._solve(prepared, deadline)
                finally:
                    prepared.folder.cleanup()
        except TimeoutError:
            raise NoAnswerError(f"no answer within {budget:g} s (the agent's timeout_s)") from None
        return self._localize(prepared, exchanges, time.monotonic() - started)

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

    def _prepare(
        self,
        sentence: Any,
        frames: Sequence[FrameInput],
        observer_view: FrameInput | None,
        cameras: Any,
        depths: Any,
    ) -> _Prepared:
        if not isinstance(sentence, str) or not sentence.strip():
            raise BadInputError("sentence: give the user's sentence as a non-empty string")
        if observer_view is not None:
            condition = Condition.GIVEN
            shown = [load_frame(observer_view, "observer_view")]
        else:
            if isinstance(frames, (str, os.PathLike, Image.Image, np.ndarray)):
                frames = [frames]  # one frame given bare
            frames = list(frames or ())
            if not frames:
                raise BadInputError("no frames: give at least one frame, or an observer_view")
            condition = Condition.INFERRED
            shown = [load_frame(f, f"frames[{i}]") for i, f in enumerate(frames)]
        cams = _aligned(cameras, len(shown), "cameras", (Camera, PinholeCamera))
        deps = _aligned(depths, len(shown), "depths", (np.ndarray,))
        for i, (im, cam) in enumerate(zip(shown, cams)):
            if cam is None:
                continue
            problem = camera_problem(cam)
            if problem is not None:
                raise BadInputError(f"cameras[{i}]: {problem}")
            if (cam.width, cam.height) != im.size:
                raise BadInputError(
                    f"cameras[{i}] describes a {cam.width}x{cam.height} image but the frame is "
                    f"{im.size[0]}x{im.size[1]}: give the camera of the original frame"
                )

        images = ImageStore()
        folder = tempfile.TemporaryDirectory(prefix="povagent-agent-")
        boxes: list[Letterbox] = []
        instance_frames: list[Frame] = []
        # The model sees benchmark-like frames; the camera it is told about is the square one.
        square_camera = unposed_square_camera()
        try:
            for i, im in enumerate(shown):
                box = Letterbox.for_size(im.size[0], im.size[1])
                stored = images.add_pil(box.apply(im, self.pad_color))
                # strategies read frames by file: write the encoded bytes once, so the file
                # hashes to the image already stored (no second encode)
                file = Path(folder.name) / f"frame_{i:03d}.png"
                file.write_bytes(images.encoded_bytes(stored.image_hash))
                boxes.append(box)
                name = "observer_view.png" if condition is Condition.GIVEN else file.name
                # the frame's own camera is the unposed square one: only a PosedSolver is
                # told the robot's cameras (below), in the world it reasons in
                instance_frames.append(Frame(i, name, file, square_camera))
        except BaseException:
            folder.cleanup()
            raise
        solver_cameras, world = None, None
        if isinstance(self.strategy, PosedSolver):
            try:
                solver_cameras, world = _solver_cameras(cams, boxes, self.plane, condition, square_camera)
            except BaseException:
                folder.cleanup()
                raise
        instance = Instance(
            house_id=AGENT_HOUSE_ID,
            pair_id=AGENT_PAIR_ID,
            direction=Direction.FRONT,  # not shown to the model; the sentence carries the relation
            condition=condition,
            sentence=sentence.strip(),
            frames=tuple(instance_frames),
            target=(float("nan"),) * 3,
            observer_object=unknown_object("Observer"),
            anchor_object=unknown_object("Anchor"),
            observer_camera=square_camera,
        )
        return _Prepared(instance, images, boxes, cams, deps, folder, solver_cameras, world)

    async def _solve(self, prepared: _Prepared, deadline: float) -> list[tuple[Request, Response]]:
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

    def _localize(self, prepared: _Prepared, exchanges: list[tuple[Request, Response]], elapsed: float) -> Localization:
        request, response = exchanges[-1]
        text = response.text or ""
        parsed: ParsedAnswer = self.parser.parse(text, request.answer)
        instance = prepared.instance
        point = parsed.point
        if point is None:
            raise _unparseable(
                f"no point could be read from the model's answer ({parsed.reason or parsed.status}): {_clip(text)}",
                text,
                parsed,
            )
        if instance.condition.uses_exploration_frames:
            k = parsed.selected_image
            if k is None or instance.selected_frame(k) is None:
                named = "no frame" if k is None else f"frame {k}"
                raise _unparseable(
                    f"the answer names {named}, but there are frames 0..{len(instance.frames) - 1}: {_clip(text)}",
                    text,
                    parsed,
                )
        else:
            k = 0
        box = prepared.boxes[k]
        square = (float(point[0]), float(point[1]))
        pixel_arr = box.to_original(np.array(square))
        pixel = (float(pixel_arr[0]), float(pixel_arr[1]))
        width, height = box.original
        goal, goal_error = None, None
        camera = prepared.cameras[k]
        solved = _solved_goal(response, camera, prepared.world, pixel)
        if solved is not None:  # a strategy that solved the geometry gives the goal itself
            goal = solved
        elif camera is not None:
            try:
                goal = back_project(camera, pixel, depth=prepared.depths[k], plane=self.plane, depth_kind=self.depth_kind)
            except GoalUnavailable as exc:
                goal_error = str(exc)
        usages = [r.usage for _, r in exchanges]
        return Localization(
            condition=instance.condition,
            frame_index=k,
            pixel=pixel,
            pixel_index=pixel_index(pixel, width, height),
            normalized=(pixel[0] / width, pixel[1] / height),
            frame_size=(width, height),
            square_point=square,
            on_padding=box.on_padding(square),
            status=parsed.status,
            reason=parsed.reason,
            repair=parsed.repair,
            raw_answer=text,
            latency_s=elapsed,
            model_latency_s=sum(r.latency_s for _, r in exchanges),
            prompt_tokens=_total(u.prompt_tokens for u in usages),
            completion_tokens=_total(u.completion_tokens for u in usages),
            cost_usd=_total(u.cost_usd for u in usages),
            retries=sum(r.retries for _, r in exchanges),
            exchanges=len(exchanges),
            goal=goal,
            goal_error=goal_error,
        )


def _solver_cameras(
    cameras: Sequence[GoalCamera | None], boxes: Sequence[Letterbox], floor: Plane, condition: Condition, unposed: Camera
) -> tuple[list[ViewCamera], SolverWorld | None]:
    """The robot's cameras as a :class:`PosedSolver` needs them: in the benchmark's world, on
    the letterboxed squares shown, and the world map they were brought in with.

    A/B triangulate with every frame's camera, so each frame needs one. C (the observer view)
    has no pose: without a camera the unposed square one stands in (only its field of view is
    read).
    """
    pinholes = [c if isinstance(c, PinholeCamera) or c is None else PinholeCamera.from_camera(c) for c in cameras]
    if condition.uses_exploration_frames:
        missing = [i for i, c in enumerate(pinholes) if c is None]
        if missing:
            raise BadInputError(
                f"cameras[{missing[0]}]: the geometric strategy triangulates with every frame's camera; "
                f"give one for each of the {len(pinholes)} frame(s) (or use another strategy)"
            )
    posed = [(i, c) for i, c in enumerate(pinholes) if c is not None]
    if not posed:
        return [unposed], None
    handed = {c.right_handed for _, c in posed}
    if len(handed) > 1:
        right = next(i for i, c in posed if c.right_handed)
        left = next(i for i, c in posed if not c.right_handed)
        raise BadInputError(
            f"cameras[{right}] is posed in a right-handed world but cameras[{left}] in a left-handed one "
            "(AI2-THOR's Camera is left-handed): give every camera in the same world"
        )
    world = SolverWorld.for_floor(floor, right_handed=handed.pop())
    solver: list[ViewCamera] = []
    for c, box in zip(pinholes, boxes):
        solver.append(unposed if c is None else c.moved(world.rotation, world.origin).letterboxed(box))
    return solver, world


def _solved_goal(response: Response, camera: GoalCamera | None, world: SolverWorld | None, pixel: tuple[float, float]) -> Goal3D | None:
    """The 3D target a strategy worked out itself (``Response.solved_point``, in the solver's
    world), back in the robot's world; ``None`` when there is none."""
    point = response.solved_point
    if point is None or camera is None or world is None:
        return None
    x, y, z = (float(v) for v in world.to_world(np.asarray(point, dtype=float)))
    distance = float(np.linalg.norm(np.array([x, y, z]) - np.asarray(camera.position, dtype=float)))
    return Goal3D(point=(x, y, z), method="geometry", distance=distance, pixel=pixel)


def _aligned(values: Any, n: int, name: str, types: tuple[type, ...]) -> list[Any]:
    """``values`` as a list of ``n`` entries (``None`` -> all ``None``; one bare value for one image)."""
    if values is None:
        return [None] * n
    if isinstance(values, types):
        values = [values]
    values = list(values)
    if len(values) != n:
        raise BadInputError(f"{name}: got {len(values)} entries for {n} image(s); give one per image shown (None allowed)")
    for i, v in enumerate(values):
        if v is not None and not isinstance(v, types):
            expected = " or ".join(t.__name__ for t in types)
            raise BadInputError(f"{name}[{i}]: expected {expected} or None, got {type(v).__name__}")
    return values


async def _cancel_other_tasks() -> None:
    """Cancel every task on the running loop but this one, and wait for them to end."""
    me = asyncio.current_task()
    others = [t for t in asyncio.all_tasks() if t is not me]
    for t in others:
        t.cancel()
    await asyncio.gather(*others, return_exceptions=True)
    await asyncio.get_running_loop().shutdown_asyncgens()


def _unparseable(message: str, raw_answer: str, parsed: ParsedAnswer) -> UnparseableAnswerError:
    """The error with the raw answer and its parse attached (a robot app may log or re-ask)."""
    return UnparseableAnswerError(message, raw_answer, parsed)


def _total(values: Any) -> Any:
    known = [v for v in values if v is not None]
    return sum(known) if known else None


def _clip(text: str, limit: int = 200) -> str:
    one_line = " ".join(text.split())
    return repr(one_line if len(one_line) <= limit else one_line[:limit] + "...")


__all__ = [
    "AskFactory",
    "FrameInput",
    "GroundingAgent",
    "Localization",
    "PinholeCamera",
    "PosedSolver",
    "Plane",
    "AGENT_RETRY",
    "default_ask_factory",
    "load_frame",
]


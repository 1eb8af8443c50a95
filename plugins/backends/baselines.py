"""Offline baselines: ``center``, ``random`` and ``oracle`` answer instantly, without a model.

They answer in the requested JSON format (``{"selected_image", "x", "y"}`` when the request
asks for a frame, else ``{"x", "y"}``) so their answers go through the same parser and scorer
as a model's.

* ``center``: the image centre (W/2, H/2), the constant guess every report shows beside the
  models. For A/B the frame follows ``frame_policy``: ``first``, ``random`` (seeded), or
  ``cycle`` (consecutive instances take consecutive frames).
* ``random``: a frame and a pixel drawn uniformly, seeded by (seed, instance id, run), so
  answers do not depend on the order requests arrive in.
* ``oracle``: the GT projected into a frame where it is visible, the one where it lies closest
  to the image centre; its mean error must be ~0 (an end-to-end check that frames, cameras and
  scoring are wired right). When no shown frame sees the GT it prefers a frame with the GT in
  front (its pixel clamped to the image), then answers the centre of a frame with the GT behind
  the camera (where the official scorer places it). For C the observer view is used the same
  way. Coordinates are written with 3 decimals.

A multiple-choice question (a request offering options) is answered with a bare label: the
``oracle`` gives the gold one, ``random`` one drawn uniformly (seeded as above); every
multiple-choice rule reads a bare label.

None of them reads files, calls a network or is worth caching.
"""

from __future__ import annotations

import _random
import hashlib
import json
import random
import zlib
from typing import Any, ClassVar, Mapping

from povagent import hookimpl
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import DIRECTIONS
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.interfaces import Backend, PermanentBackendError
from povagent.scoring.normalized_l2 import project_ground_truth

FRAME_POLICIES: tuple[str, ...] = ("first", "random", "cycle")


def request_run(request: Request) -> int:
    """The run index a request belongs to (0 when the request does not say)."""
    # Request carries the run for offline baselines when the runner sets it (see the report)
    run = request.run
    return run if isinstance(run, int) else 0


def answer_text(request: Request, frame: int | None, x: float, y: float) -> str:
    """The answer as the JSON the request asked for, coordinates with at most 3 decimals."""
    doc: dict[str, Any] = {}
    if request.answer.asks_frame:
        doc["selected_image"] = frame if frame is not None else 0
    doc["x"] = _num(x)
    doc["y"] = _num(y)
    return json.dumps(doc)


def _num(v: float) -> float | int:
    r = round(float(v), 3)
    return int(r) if r.is_integer() else r


def shown_frame_count(request: Request) -> int:
    """How many frames the request shows (what ``selected_image`` indexes)."""
    return max(1, int(request.answer.n_frames))


def seeded_rng(*parts: object) -> random.Random:
    """A generator seeded from ``parts`` (stable across processes and Python hash seeds)."""
    digest = hashlib.sha256("|".join(map(str, parts)).encode()).digest()
    # ``random.Random(seed)``, the same state, made without the Python layer of ``seed``
    # around the C seeding of an int (what ``Random.seed`` calls for one): a run seeds one a key
    rng = _new_random(random.Random)
    _seed_int(rng, int.from_bytes(digest[:8], "big"))
    rng.gauss_next = None  # type: ignore[attr-defined]  # (Random's own attribute, set by its seed)
    return rng


_new_random = random.Random.__new__
_seed_int = _random.Random.seed


def _instance_id(request: Request) -> str:
    return request.instance.id if request.instance is not None else request.content_hash()


def _instant(text: str, name: str) -> Response:
    return Response(text=text, usage=Usage(prompt_tokens=0, completion_tokens=0, cost_usd=0.0), latency_s=0.0, model=name)


class CenterBaseline(Backend):
    """Always the image centre; for A/B the frame chosen by ``frame_policy``."""

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def __init__(self, frame_policy: str = "first", seed: int = 0) -> None:
        if frame_policy not in FRAME_POLICIES:
            raise ConfigError(f"backend 'center': option 'frame_policy': {frame_policy!r} is not one of {', '.join(FRAME_POLICIES)}")
        self.frame_policy = frame_policy
        self.seed = int(seed)

    def identity(self) -> Mapping[str, Any]:
        """Name, frame policy and seed."""
        return {"backend": "center", "frame_policy": self.frame_policy, "seed": self.seed}

    def choose_frame(self, request: Request) -> int:
        """The frame index the policy picks for this request."""
        n = shown_frame_count(request)
        if self.frame_policy == "first":
            return 0
        if self.frame_policy == "random":
            return seeded_rng(self.seed, "center", _instance_id(request), request_run(request)).randrange(n)
        return (instance_ordinal(request.instance) + request_run(request)) % n if request.instance else 0

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """The centre pixel of the chosen frame."""
        spec = request.answer
        frame = self.choose_frame(request) if spec.asks_frame else None
        return _instant(answer_text(request, frame, spec.width / 2, spec.height / 2), "center")


def instance_ordinal(instance: Instance) -> int:
    """A stable number that steps by one between consecutive instances of a house.

    Instances run in (pair, direction) order, so pair number x 4 + direction index makes the
    ``cycle`` policy move to the next frame from one instance to the next. Non-numeric pair
    ids use a CRC of the id (stable, though no longer consecutive).
    """
    try:
        pair = int(instance.pair_id)
    except ValueError:
        pair = zlib.crc32(instance.pair_id.encode())
    return pair * len(DIRECTIONS) + DIRECTIONS.index(instance.povbench_direction)


class RandomBaseline(Backend):
    """A uniform frame and pixel, seeded by (seed, instance id, run)."""

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def __init__(self, seed: int = 0) -> None:
        self.seed = int(seed)

    def identity(self) -> Mapping[str, Any]:
        """Name and seed."""
        return {"backend": "random", "seed": self.seed}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """A reproducible uniform guess (integer pixels in range)."""
        spec = request.answer
        rng = seeded_rng(self.seed, "random", _instance_id(request), request_run(request))
        if spec.choices:  # a multiple-choice question: a uniform label
            return _instant(rng.choice(spec.choices)[0], "random")
        frame = rng.randrange(shown_frame_count(request)) if spec.asks_frame else None
        x, y = rng.randrange(spec.width), rng.randrange(spec.height)
        return _instant(answer_text(request, frame, x, y), "random")


def _rank(frame: Frame, target: tuple[float, float, float]) -> tuple[int, float, float, float]:
    """Sort key: GT in frame first, then in front, then behind; then closest to the centre."""
    gt = project_ground_truth(target, frame.camera)
    tier = 0 if gt.in_frame else (2 if gt.behind else 1)
    return (tier, (gt.u - 0.5) ** 2 + (gt.v - 0.5) ** 2, gt.u, gt.v)


def oracle_answer(instance: Instance, n_shown: int) -> tuple[int, float, float]:
    """(frame index, u, v) of the oracle's answer in normalized image coordinates (clamped)."""
    frames = instance.frames[: max(1, n_shown)]
    if not frames:
        raise PermanentBackendError(f"instance {instance.id} shows no frames")
    ranked = sorted(range(len(frames)), key=lambda i: (_rank(frames[i], instance.target)[:2], i))
    best = ranked[0]
    _, _, u, v = _rank(frames[best], instance.target)
    return best, min(1.0, max(0.0, u)), min(1.0, max(0.0, v))


class OracleBaseline(Backend):
    """The projected ground truth: the metric's floor."""

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def identity(self) -> Mapping[str, Any]:
        """Name only: the oracle has no options."""
        return {"backend": "oracle"}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer the GT's pixel in the frame where it lies most centrally."""
        instance = request.instance
        if instance is None:
            raise PermanentBackendError("the oracle needs request.instance (the ground truth); the strategy sent none")
        spec = request.answer
        if spec.choices:  # a multiple-choice question: the gold label
            if instance.question is None:
                raise PermanentBackendError(f"instance {instance.id} asks no question, yet the request offers options")
            return _instant(instance.question.gold, "oracle")
        if instance.numeric is not None:  # a numerical question: the gold number, as float() reads it back
            return _instant(repr(instance.numeric.gold), "oracle")
        n_shown = shown_frame_count(request) if spec.asks_frame else 1
        frame, u, v = oracle_answer(instance, n_shown)
        # clamp to the last pixel: u = 1.0 exactly is only reached by a GT out of every frame
        x = min(u * spec.width, spec.width - 1)
        y = min(v * spec.height, spec.height - 1)
        return _instant(answer_text(request, frame if spec.asks_frame else None, x, y), "oracle")


@hookimpl
def register_backends(register) -> None:
    """Contribute the offline baselines."""
    register("center", CenterBaseline, description="Image centre (A/B frame: first, random or cycle); no model")
    register("random", RandomBaseline, description="Uniform random frame and pixel, seeded per instance and run")
    register("oracle", OracleBaseline, description="Projected ground truth: the metric's floor and a wiring check")

"""The ``simulated`` backend: a perception simulator, not a model.

It answers the ``geometric`` strategy's sub-questions (``Request.question``) from the dataset's
own records, with noise as strong as asked, so the solver can be studied offline:

* ``read``: the observer's furniture (``objectType`` of ``object_observer``), the anchor
  (``landmark_type``) and the direction of the instance. In condition A (Inferred), with
  probability ``wrong_furniture_rate`` the observer is another furniture type of the same house
  (one its records hold a box for, so it can be pointed at).
* ``surface``: the kind of ``stage3[dir].surface`` (floor, the anchor itself, another object);
  with probability ``wrong_surface_rate`` one of the two others.
* ``locate``: for every shown frame whose record lists the object as seen
  (``object_in_frame_hits``; the observer view always looks at its anchor) and where the centre
  of its box projects inside the image, the projected centre and the 2D box around the projected
  box, each coordinate with Gaussian noise of ``pixel_sigma`` pixels; each such frame is missed
  with probability ``miss_rate``.

Answers are deterministic per (``seed``, instance, run, sub-question): the order requests
arrive in changes nothing. A request without a question it knows (any free-form prompt) is
refused with a permanent error: the simulator never pretends to be a model. Its answers say
``model: "simulation"`` and the reports label it a simulation.

The records are read from the house folder the instance's frames are in (the release layout's
``artifacts/<house>/``), or from the ``dataset`` option's folder.

:class:`SimulatedScene` is the same simulator for a scene given in code rather than a dataset:
object boxes in a robot's world, seen through the robot's own cameras (any convention, any frame
size), answering in the letterboxed square the GroundingAgent shows; it lets a robot app (and
``examples/robot_app.py``) run the geometric agent end to end offline.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, ClassVar, Mapping, Sequence

import numpy as np

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent.dataset.loader import House
from povagent.dataset.release_models import PairEntry, SceneObject
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.geometry.box_outline import NEAR_PLANE, outline
from povagent.geometry.camera import ViewCamera
from povagent.geometry.letterbox import Letterbox
from povagent.geometry.placement import SURFACE_KINDS, surface_kind
from povagent.interfaces import Backend, PermanentBackendError
from povagent_plugins.backends.records import HouseRecords

#: The label every answer carries in ``Response.model``.
SIMULATION_LABEL = "simulation"


def rate_option(backend: str, name: str, value: Any) -> float:
    """A simulation's option ``name`` that is a probability or a share: a number in [0, 1]."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= float(value) <= 1.0:
        raise ConfigError(f"backend '{backend}': option '{name}' must be a number in [0, 1], got {value!r}")
    return float(value)


def noise_options(backend: str, pixel_sigma: Any, seed: Any) -> tuple[float, int]:
    """A simulation's ``pixel_sigma`` (a number >= 0, in pixels) and ``seed`` (an integer)."""
    if isinstance(pixel_sigma, bool) or not isinstance(pixel_sigma, (int, float)) or not pixel_sigma >= 0:
        raise ConfigError(f"backend '{backend}': option 'pixel_sigma' must be a number >= 0 (pixels), got {pixel_sigma!r}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ConfigError(f"backend '{backend}': option 'seed' must be an integer, got {seed!r}")
    return float(pixel_sigma), seed


def seeded_generator(*parts: object) -> np.random.Generator:
    """A generator seeded from ``parts`` (stable across processes and Python hash seeds)."""
    digest = hashlib.sha256("|".join(str(p) for p in parts).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "big"))


def box_outline(camera: ViewCamera, obj: SceneObject) -> tuple[float, float, float, float] | None:
    """The 2D box (pixels, clipped to the image) around an object's projected box, from the
    part in front of the camera; ``None`` when none of it is in front or in the image."""
    corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float)
    return outline(camera, corners.min(axis=0), corners.max(axis=0))


def _centre(obj: SceneObject) -> tuple[float, float, float]:
    return obj.raw_metadata.axisAlignedBoundingBox.center.as_tuple()


class SimulatedPerception(Backend):
    """Answers the geometric strategy's sub-questions from the records, with noise.

    Options: ``pixel_sigma`` (px, >= 0), ``miss_rate``, ``wrong_furniture_rate`` (condition A
    only), ``wrong_surface_rate`` (each in [0, 1]), ``seed``, ``dataset`` (the dataset folder,
    when the frames are not inside the release layout).
    """

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def __init__(
        self,
        pixel_sigma: float = 0.0,
        miss_rate: float = 0.0,
        wrong_furniture_rate: float = 0.0,
        wrong_surface_rate: float = 0.0,
        seed: int = 0,
        dataset: str | None = None,
    ) -> None:
        self.pixel_sigma, self.seed = noise_options("simulated", pixel_sigma, seed)
        self.miss_rate = rate_option("simulated", "miss_rate", miss_rate)
        self.wrong_furniture_rate = rate_option("simulated", "wrong_furniture_rate", wrong_furniture_rate)
        self.wrong_surface_rate = rate_option("simulated", "wrong_surface_rate", wrong_surface_rate)
        self.dataset = Path(dataset).expanduser() if dataset else None
        self._records = HouseRecords("simulated", self.dataset)

    def identity(self) -> Mapping[str, Any]:
        """Name, ``simulation: True`` and every noise option."""
        return {
            "backend": "simulated",
            "simulation": True,
            "pixel_sigma": self.pixel_sigma,
            "miss_rate": self.miss_rate,
            "wrong_furniture_rate": self.wrong_furniture_rate,
            "wrong_surface_rate": self.wrong_surface_rate,
            "seed": self.seed,
        }

    # -- records ------------------------------------------------------------------------------
    def house_of(self, instance: Instance) -> House:
        """The house records of ``instance`` (read once per house folder)."""
        return self._records.house_of(instance)

    # -- answering ----------------------------------------------------------------------------
    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer one sub-question; refuse anything else."""
        question = request.question
        kind = question.get("kind") if isinstance(question, Mapping) else None
        handler = {"read": self._read, "surface": self._surface, "locate": self._locate}.get(str(kind))
        if handler is None or not isinstance(question, Mapping):
            raise PermanentBackendError(
                "the simulated backend is a perception simulation, not a model: it answers only the 'geometric' "
                f"strategy's sub-questions (Request.question kind read, surface or locate), and this request carries "
                f"{'no question' if question is None else f'question kind {kind!r}'}; use strategy: geometric"
            )
        instance = request.instance
        if instance is None:
            raise PermanentBackendError("the simulated backend needs request.instance (it answers from the records)")
        house = self.house_of(instance)
        pair = house.pairs.get(instance.pair_id)
        if pair is None:
            raise PermanentBackendError(f"simulated backend: no pair {instance.pair_id!r} in the records of {instance.house_id}")
        rng = seeded_generator(self.seed, instance.id, request.run, json.dumps(dict(question), sort_keys=True, default=str))
        answer = handler(question, instance, house, pair, rng)
        return Response(text=json.dumps(answer), usage=Usage(0, 0, 0.0), latency_s=0.0, model=SIMULATION_LABEL)

    def _read(self, question: Mapping[str, Any], instance: Instance, house: House, pair: PairEntry, rng: np.random.Generator) -> dict[str, Any]:
        answer: dict[str, Any] = {}
        asks = question.get("asks") or ("observer", "anchor", "direction")
        if "observer" in asks:
            observer = pair.object_observer.object_type
            wrong = rng.random() < self.wrong_furniture_rate
            if wrong and str(instance.condition) == "a":
                others = sorted({o.object_type for o in house_objects(house)} - {observer, pair.landmark_type})
                if others:
                    observer = others[int(rng.integers(len(others)))]
            answer["observer"] = observer
        if "anchor" in asks:
            answer["anchor"] = pair.object_landmark.object_type
        if "direction" in asks:
            answer["direction"] = str(instance.direction)
        return answer

    def _surface(self, question: Mapping[str, Any], instance: Instance, house: House, pair: PairEntry, rng: np.random.Generator) -> dict[str, Any]:
        judgement = pair.stage3.get(instance.povbench_direction)
        kind = surface_kind(judgement.surface if judgement else None, pair.object_landmark.object_type)
        if rng.random() < self.wrong_surface_rate:
            others = [k for k in SURFACE_KINDS if k != kind]
            kind = others[int(rng.integers(len(others)))]
        return {"surface": kind}

    def _locate(self, question: Mapping[str, Any], instance: Instance, house: House, pair: PairEntry, rng: np.random.Generator) -> dict[str, Any]:
        obj = pointed_object(str(question.get("object", "")), str(question.get("role", "")), house, pair)
        if obj is None:
            return {"detections": []}
        given = not instance.povbench_condition.uses_exploration_frames
        detections = []
        for index, frame in enumerate(instance.frames):
            seen_by_record = given or (index < len(house.exploration) and obj.objectId in house.exploration[index].object_in_frame_hits)
            miss = rng.random() < self.miss_rate  # drawn for every frame: noise does not shift with visibility
            noise = rng.normal(0.0, self.pixel_sigma, size=6) if self.pixel_sigma > 0 else np.zeros(6)
            if not seen_by_record or miss:
                continue
            cam = frame.camera
            u, v, depth = cam.project_point(_centre(obj))
            if not (depth > NEAR_PLANE and 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
                continue
            box = box_outline(cam, obj)
            w, h = cam.width - 1.0, cam.height - 1.0
            x = float(np.clip(u * cam.width + noise[0], 0, w))
            y = float(np.clip(v * cam.height + noise[1], 0, h))
            entry: dict[str, Any] = {"image": index, "x": round(x, 1), "y": round(y, 1)}
            if box is not None:
                x0, x1 = sorted(float(np.clip(box[k] + noise[2 + k], 0, w)) for k in (0, 2))
                y0, y1 = sorted(float(np.clip(box[k] + noise[2 + k], 0, h)) for k in (1, 3))
                entry["box"] = [round(x0, 1), round(y0, 1), round(x1, 1), round(y1, 1)]
            detections.append(entry)
        return {"detections": detections}


def house_objects(house: House) -> list[SceneObject]:
    """Every object the house's records hold a box for (observers and anchors), by objectId."""
    objects: dict[str, SceneObject] = {}
    for pair in house.pairs.values():
        for obj in (pair.object_observer, pair.object_landmark):
            objects.setdefault(str(obj.objectId), obj)
    return [objects[k] for k in sorted(objects)]


def pointed_object(object_type: str, role: str, house: House, pair: PairEntry) -> SceneObject | None:
    """The object a locate question means: the pair's observer or anchor when the type and role
    match, else the house's first recorded object of that type (a wrongly read furniture)."""
    if role == "observer" and object_type == pair.object_observer.object_type:
        return pair.object_observer
    if role == "anchor" and object_type == pair.object_landmark.object_type:
        return pair.object_landmark
    for obj in (pair.object_observer, pair.object_landmark, *house_objects(house)):
        if obj.object_type == object_type:
            return obj
    return None


class SimulatedScene(Backend):
    """The perception simulator for one known scene seen through a robot's cameras.

    ``objects`` maps an object type to its axis-aligned box ``(low corner, high corner)`` in the
    robot's world; ``cameras`` are the cameras of the frames the agent is given (in order; any
    :class:`~povagent.geometry.camera.ViewCamera`: a ``PinholeCamera`` in any convention or an
    AI2-THOR ``Camera``). The read and surface sub-questions get ``anchor``, ``direction``,
    ``observer`` and ``surface`` as given; a locate question gets, for every frame whose image
    shows the object's centre (no occlusion is simulated), the projected centre and the box
    around the projected box, mapped into the letterboxed square the agent shows the model, with
    Gaussian noise of ``pixel_sigma`` (square pixels). Deterministic per ``seed`` and question;
    any other prompt is refused, as by :class:`SimulatedPerception`.
    """

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def __init__(
        self,
        objects: Mapping[str, tuple[Sequence[float], Sequence[float]]],
        cameras: Sequence[ViewCamera],
        *,
        anchor: str,
        direction: str,
        surface: str,
        observer: str | None = None,
        pixel_sigma: float = 0.0,
        seed: int = 0,
    ) -> None:
        if surface not in SURFACE_KINDS:
            raise ValueError(f"surface must be one of {', '.join(SURFACE_KINDS)}, got {surface!r}")
        if not pixel_sigma >= 0:
            raise ValueError(f"pixel_sigma must be >= 0 (pixels), got {pixel_sigma!r}")
        self.objects = {k: (np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)) for k, (lo, hi) in objects.items()}
        self.cameras = list(cameras)
        self.read = {"observer": observer, "anchor": anchor, "direction": direction}
        self.surface = surface
        self.pixel_sigma = float(pixel_sigma)
        self.seed = int(seed)

    def identity(self) -> Mapping[str, Any]:
        """Name, ``simulation: True``, the noise and the seed."""
        return {"backend": "simulated-scene", "simulation": True, "pixel_sigma": self.pixel_sigma, "seed": self.seed}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Answer one sub-question about the scene; refuse anything else."""
        question = request.question if isinstance(request.question, Mapping) else {}
        kind = question.get("kind")
        if kind == "read":
            asks = question.get("asks") or tuple(self.read)
            answer: dict[str, Any] = {k: v for k, v in self.read.items() if k in asks and v is not None}
        elif kind == "surface":
            answer = {"surface": self.surface}
        elif kind == "locate":
            rng = seeded_generator(self.seed, request.run, json.dumps(dict(question), sort_keys=True, default=str))
            answer = {"detections": self._detections(str(question.get("object", "")), rng)}
        else:
            raise PermanentBackendError(
                "the simulated scene is a perception simulation, not a model: it answers only the 'geometric' "
                f"strategy's sub-questions, and this request carries {'no question' if not question else f'question kind {kind!r}'}"
            )
        return Response(text=json.dumps(answer), usage=Usage(0, 0, 0.0), latency_s=0.0, model=SIMULATION_LABEL)

    def _detections(self, object_type: str, rng: np.random.Generator) -> list[dict[str, Any]]:
        box3d = self.objects.get(object_type)
        found: list[dict[str, Any]] = []
        for index, cam in enumerate(self.cameras):
            noise = rng.normal(0.0, self.pixel_sigma, size=6) if self.pixel_sigma > 0 else np.zeros(6)
            if box3d is None:
                continue
            lo, hi = box3d
            u, v, depth = cam.project_point((lo + hi) / 2.0)
            if not (depth > NEAR_PLANE and 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
                continue
            square = Letterbox.for_size(cam.width, cam.height)
            last = square.size - 1.0
            x, y = square.to_square(np.array([u * cam.width, v * cam.height])) + noise[:2]
            entry: dict[str, Any] = {"image": index, "x": round(float(np.clip(x, 0, last)), 2), "y": round(float(np.clip(y, 0, last)), 2)}
            box = outline(cam, lo, hi)
            if box is not None:
                corners = square.to_square(np.array([box[:2], box[2:]])).ravel() + noise[2:]
                x0, x1 = sorted(float(np.clip(corners[k], 0, last)) for k in (0, 2))
                y0, y1 = sorted(float(np.clip(corners[k], 0, last)) for k in (1, 3))
                entry["box"] = [round(x0, 2), round(y0, 2), round(x1, 2), round(y1, 2)]
            found.append(entry)
        return found


@hookimpl
def register_backends(register) -> None:
    """Contribute the perception simulator."""
    register(
        "simulated",
        SimulatedPerception,
        description="A perception SIMULATION (not a model): answers the geometric strategy's sub-questions from the records, with noise",
    )

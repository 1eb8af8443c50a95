"""The ``planted`` backend: a behaviour SIMULATION, not a model, that plants known failures.

It answers the ordinary single-answer strategies' questions (``basic``, ``cot``, ``spatial-cot``,
``o-plot``, ``oa-plot``) in their JSON format, ``{"selected_image", "x", "y"}`` or ``{"x", "y"}``,
from the dataset's own records, so the diagnostics (``diagnose``, ``relation``) can be checked
against behaviour whose shares are known:

* with probability ``egocentric``: the egocentric target (:mod:`povagent.geometry.counterfactual`:
  the placement rule with the answered frame's camera axes instead of the observer's);
* with probability ``mirror``: the mirrored target (left and right swapped);
* with probability ``random_frame``: a uniformly random pixel in a random frame that does not
  show the anchor (any frame when every frame shows it; in C, with one frame, a random pixel);
* otherwise the ground truth.

A perception probe's question (``Request.question`` kind ``probe``: ``probe-anchor``,
``probe-observer``) is answered with perfect perception: the probed object's box centre as the
official metric places a point in the frame asked about, plus the pixel noise.

The behaviour is drawn once per (``seed``, instance, run). Except for ``random_frame`` the frame
is chosen before the behaviour and without it: among the shown frames whose record lists the
anchor as seen (``object_in_frame_hits``), the one where the anchor's centre lies nearest the
image centre (any frame when none shows it; C: the observer view). The point is the target as the
official metric projects it (clamped, behind the camera -> centre), plus Gaussian noise of
``pixel_sigma`` pixels per axis, kept inside the image. Answers say ``model: "planted
simulation"`` and reports label the backend a simulation. The records are read from the house
folder of the instance's frames, or from the ``dataset`` option's folder.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np

from povagent import hookimpl
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.loader import placement_case
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.geometry.counterfactual import egocentric_target, mirrored_target
from povagent.interfaces import Backend, PermanentBackendError
from povagent.scoring.normalized_l2 import clamp_unit, project_ground_truth
from povagent_plugins.backends.baselines import answer_text, request_run, shown_frame_count
from povagent_plugins.backends.records import HouseRecords
from povagent_plugins.backends.simulated import noise_options, rate_option, seeded_generator

#: The label every answer carries in ``Response.model``.
PLANTED_LABEL = "planted simulation"
#: The behaviours a planted answer may follow.
BEHAVIOURS: tuple[str, ...] = ("egocentric", "mirror", "random_frame", "truth")


def anchor_frame(instance: Instance, frames: tuple[Frame, ...]) -> int:
    """The shown frame that shows the anchor with its centre nearest the image centre."""
    anchor_id = str(instance.anchor_object.objectId)
    centre = instance.anchor_object.raw_metadata.axisAlignedBoundingBox.center.as_tuple()
    seeing = [i for i, f in enumerate(frames) if anchor_id in f.in_frame_hits] or list(range(len(frames)))

    def rank(i: int) -> tuple[int, float, int]:
        gt = project_ground_truth(centre, frames[i].camera)
        return (1 if gt.behind else 0, (gt.u - 0.5) ** 2 + (gt.v - 0.5) ** 2, i)

    return min(seeing, key=rank)


class PlantedBehaviour(Backend):
    """Answers with planted shares of egocentric, mirrored and random-frame behaviour.

    Options: ``egocentric``, ``mirror``, ``random_frame`` (shares in [0, 1], summing to at most
    1), ``pixel_sigma`` (px, >= 0), ``seed``, ``dataset`` (the dataset folder, when the frames
    are not inside the release layout).
    """

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True
    answers_in_process: ClassVar[bool] = True  # no I/O, no await: answered a chunk at a time

    def __init__(
        self,
        egocentric: float = 0.0,
        mirror: float = 0.0,
        random_frame: float = 0.0,
        pixel_sigma: float = 5.0,
        seed: int = 0,
        dataset: str | None = None,
    ) -> None:
        shares = {"egocentric": egocentric, "mirror": mirror, "random_frame": random_frame}
        self.shares = {name: rate_option("planted", name, value) for name, value in shares.items()}
        if sum(self.shares.values()) > 1.0 + 1e-9:
            raise ConfigError(f"backend 'planted': the shares egocentric + mirror + random_frame must not exceed 1, got {self.shares}")
        self.pixel_sigma, self.seed = noise_options("planted", pixel_sigma, seed)
        self._records = HouseRecords("planted", Path(dataset).expanduser() if dataset else None)

    def identity(self) -> Mapping[str, Any]:
        """Name, ``simulation: True`` and every option that changes answers."""
        return {"backend": "planted", "simulation": True, **self.shares, "pixel_sigma": self.pixel_sigma, "seed": self.seed}

    def behaviour(self, instance: Instance, run: int) -> str:
        """The behaviour drawn for one (instance, run)."""
        draw = float(seeded_generator(self.seed, "behaviour", instance.id, run).random())
        edge = 0.0
        for name in BEHAVIOURS[:-1]:
            edge += self.shares[name]
            if draw < edge:
                return name
        return "truth"

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """One planted answer in the JSON format the request asks for."""
        instance = request.instance
        if request.question is not None:
            if request.question.get("kind") == "probe" and instance is not None:
                return self._probe(request, instance)
            raise PermanentBackendError(
                "the planted backend is a behaviour simulation, not a model: it answers single-answer strategies "
                "(basic, cot, spatial-cot, o-plot, oa-plot) and the perception probes, not the geometric strategy's sub-questions"
            )
        if instance is None:
            raise PermanentBackendError("the planted backend needs request.instance (it answers from the records)")
        run = request_run(request)
        spec = request.answer
        frames = instance.frames[: shown_frame_count(request)] if spec.asks_frame else instance.frames[:1]
        rng = seeded_generator(self.seed, "answer", instance.id, run)
        behaviour = self.behaviour(instance, run)
        if behaviour == "random_frame":
            anchor_id = str(instance.anchor_object.objectId)
            elsewhere = [i for i, f in enumerate(frames) if anchor_id not in f.in_frame_hits] or list(range(len(frames)))
            index = elsewhere[int(rng.integers(len(elsewhere)))]
            x, y = float(rng.uniform(0, spec.width - 1)), float(rng.uniform(0, spec.height - 1))
            return self._answer(request, index, x, y)
        index = anchor_frame(instance, frames)
        frame = frames[index]
        target = np.asarray(instance.target, dtype=float)
        if behaviour != "truth":
            house = self._records.house_of(instance)
            pair = house.pairs.get(instance.pair_id)
            if pair is None:
                raise PermanentBackendError(f"planted backend: no pair {instance.pair_id!r} in the records of {instance.house_id}")
            case = placement_case(pair, instance.povbench_direction)
            target = egocentric_target(case, frame.camera) if behaviour == "egocentric" else mirrored_target(case)
        gt = project_ground_truth(target, frame.camera)
        noise = rng.normal(0.0, self.pixel_sigma, size=2) if self.pixel_sigma > 0 else np.zeros(2)
        x = min(max(clamp_unit(gt.u) * spec.width + float(noise[0]), 0.0), spec.width - 1.0)
        y = min(max(clamp_unit(gt.v) * spec.height + float(noise[1]), 0.0), spec.height - 1.0)
        return self._answer(request, index, x, y)

    def _probe(self, request: Request, instance: Instance) -> Response:
        """A probe (``probe-anchor``, ``probe-observer``): perception is planted perfect, so the
        point is the object's box centre as the official metric places a point in the frame
        asked about, plus the pixel noise (nothing else is planted in it)."""
        question = request.question or {}
        index = question.get("frame")
        frame = instance.frames[index] if isinstance(index, int) and 0 <= index < len(instance.frames) else instance.frames[0]
        obj = instance.anchor_object if question.get("role") == "anchor" else instance.observer_object
        gt = project_ground_truth(obj.raw_metadata.axisAlignedBoundingBox.center.as_tuple(), frame.camera)
        rng = seeded_generator(self.seed, "probe", instance.id, request_run(request), question.get("role"))
        noise = rng.normal(0.0, self.pixel_sigma, size=2) if self.pixel_sigma > 0 else np.zeros(2)
        spec = request.answer
        x = min(max(clamp_unit(gt.u) * spec.width + float(noise[0]), 0.0), spec.width - 1.0)
        y = min(max(clamp_unit(gt.v) * spec.height + float(noise[1]), 0.0), spec.height - 1.0)
        return Response(text=json.dumps({"x": round(x, 2), "y": round(y, 2)}), usage=Usage(0, 0, 0.0), latency_s=0.0, model=PLANTED_LABEL)

    def _answer(self, request: Request, index: int, x: float, y: float) -> Response:
        frame = index if request.answer.asks_frame else None
        return Response(text=answer_text(request, frame, x, y), usage=Usage(0, 0, 0.0), latency_s=0.0, model=PLANTED_LABEL)


@hookimpl
def register_backends(register) -> None:
    """Contribute the planted behaviour simulator."""
    register(
        "planted",
        PlantedBehaviour,
        description="A behaviour SIMULATION (not a model): answers from the records with planted egocentric/mirror/random-frame shares",
    )


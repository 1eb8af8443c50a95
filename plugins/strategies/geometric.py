"""The ``geometric`` strategy: the model perceives, geometry reasons (multi-turn).

The paper finds that spelling out the observer-relative reasoning helps, and that models still
fail at the geometry. Here the model is asked only what it is good at, each as an ordinary
request with an answer schema, and the geometry is done exactly:

1. *read* the sentence: which furniture the speaker was at (A: inferred from the activity; B:
   stated, still read), the anchor, and the direction;
2. *surface*: what the target rests on (the floor, the anchor, or another object);
3. *locate* the anchor, then (A/B) the observer's furniture: in every frame where the model
   sees it, its centre pixel and bounding box.

With the frames' cameras (the release's ``exploration_log.json``; a robot's own poses) the
anchor and the observer are triangulated (where the speaker stood, when the caller knows it,
stands in for the observer's furniture, which is then not asked for) (one view: a ray against the type's usual centre
height, :mod:`povagent.geometry.triangulation`), the anchor's box is fitted to its outlines,
the target is placed by the benchmark's own rules (:mod:`povagent.geometry.placement`), and
the frame showing it best is chosen. Condition C (the observer view, no pose) is solved in the
image plane from the anchor's box (:mod:`povagent.geometry.given_view`).

Each request carries ``Request.question``, a machine-readable form of the sub-question that
model backends ignore and the ``simulated`` backend answers. The final answer is worked out,
not asked: it is returned as the last turn with ``by_strategy`` set, its text the answer's JSON
followed by the solver's account of every step, fallbacks included (a step the model fails
falls back, and the account says how). This module must not score or read dataset records.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Message, Request, Response, TextPart
from povagent.exchange.prompts import frame_values, render
from povagent.geometry.camera import ViewCamera
from povagent.geometry.directions import DIRECTION_NAMES, DIRECTION_REGISTRY, direction_spec, spec_of
from povagent.geometry.given_view import solve_given_view
from povagent.geometry.ground_truth import anchor_keywords
from povagent.geometry.placement import SURFACE_KINDS, AnchorEstimate, choose_frame, place_target
from povagent.geometry.size_priors import size_prior
from povagent.geometry.triangulation import MIN_RAY_ANGLE_DEG, Outline, Sighting, fit_box, locate
from povagent.interfaces import Ask, PlannedTurn, Strategy, earlier_answer
from povagent_plugins.strategies.basic import generation_options
from povagent_plugins.strategies.layout import answer_spec, image_parts, shown_images

#: The ``kind`` of each sub-question (``Request.question["kind"]``).
READ, SURFACE, LOCATE = "read", "surface", "locate"
#: ``Request.question["kind"]`` of the final turn (worked out by the solver, never sent).
FINAL = "final"
#: The key of the final answer's JSON holding the 3D target (A/B).
TARGET_3D = "target_3d"
#: What the final turn's text says after the answer's JSON.
ACCOUNT_HEADER = "geometric solver (answer worked out from the answers above, not asked):"
#: The direction taken when the answer names none: the one nearly every pair has (the paper: 97%).
FALLBACK_DIRECTION = "front"
#: Words a model may use for a direction (the registry's names and synonyms), mapped to its name.
DIRECTION_WORDS = {word: spec.name for spec in DIRECTION_REGISTRY for word in spec.words}
#: Held to the triangulated centre within this (m) when fitting the anchor's box; the height
#: prior's centre is looser.
TRIANGULATED_CENTRE_SIGMA = 0.05
PRIOR_CENTRE_SIGMA = 0.5


def object_words(object_type: str) -> str:
    """How prompts name a type: ``SideTable`` -> ``side table`` (the ground-truth keywords)."""
    return anchor_keywords(object_type)[0]


def known_types() -> tuple[str, ...]:
    """The paper's 31 observer/anchor categories (the types the read question offers)."""
    from povagent.generate.assets import OBSERVER_ANCHOR_CATEGORIES

    return OBSERVER_ANCHOR_CATEGORIES


def normalize_type(value: Any) -> str | None:
    """A model's furniture name as a known type (``"side table"`` -> ``SideTable``); any other
    non-empty name is kept as written (it is still pointed at; its size is a generic prior)."""
    if not isinstance(value, str) or not value.strip():
        return None
    squashed = re.sub(r"[^a-z]", "", value.lower())
    for t in known_types():
        if squashed == t.lower() or any(squashed == re.sub(r"[^a-z]", "", k) for k in anchor_keywords(t)):
            return t
    return value.strip()


def normalize_direction(value: Any) -> str | None:
    """A model's direction as one of the registry's names (``None`` if none)."""
    if not isinstance(value, str):
        return None
    text = value.strip().lower()
    if text in DIRECTION_WORDS:
        return DIRECTION_WORDS[text]
    for word, direction in DIRECTION_WORDS.items():
        if re.search(rf"\b{word}\b", text):
            return direction
    return None


def json_object(text: str | None) -> dict[str, Any] | None:
    """The first JSON object in a model's answer (fenced or not, prose around it allowed)."""
    if not text:
        return None
    decoder = json.JSONDecoder()
    for match in re.finditer(r"\{", text):
        try:
            value, _ = decoder.raw_decode(text, match.start())
        except json.JSONDecodeError:
            continue
        if isinstance(value, dict):
            return value
    return None


@dataclass(frozen=True)
class Detection:
    """One sighting the model reported: frame index, centre pixel, and box (if it gave one)."""

    frame: int
    pixel: tuple[float, float]
    box: tuple[float, float, float, float] | None


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def parse_detections(answer: dict[str, Any] | None, n_frames: int, width: int, height: int) -> tuple[list[Detection], int]:
    """The usable detections of a locate answer and how many entries were dropped (a frame
    index out of range, no point and no box, a frame named twice). Pixels are clamped into
    the image; a box's corners are put in order."""
    raw = answer.get("detections") if isinstance(answer, dict) else None
    if not isinstance(raw, list):
        return [], 0
    out: list[Detection] = []
    seen: set[int] = set()
    dropped = 0
    for entry in raw:
        frame = _number(entry.get("image")) if isinstance(entry, dict) else None
        if frame is None or int(frame) != frame or not 0 <= int(frame) < n_frames or int(frame) in seen:
            dropped += 1
            continue
        box = None
        coords = entry.get("box")
        if isinstance(coords, list) and len(coords) == 4 and all(_number(c) is not None for c in coords):
            x0, y0, x1, y1 = (float(c) for c in coords)
            box = (
                _clamp(min(x0, x1), width), _clamp(min(y0, y1), height), _clamp(max(x0, x1), width), _clamp(max(y0, y1), height)
            )
        x, y = _number(entry.get("x")), _number(entry.get("y"))
        if x is None or y is None:
            if box is None:
                dropped += 1
                continue
            x, y = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0
        seen.add(int(frame))
        out.append(Detection(int(frame), (_clamp(x, width), _clamp(y, height)), box))
    return out, dropped


def _clamp(v: float, size: int) -> float:
    return min(max(float(v), 0.0), size - 1.0)


@dataclass
class Account:
    """What the solver did, step by step, and where it fell back (written into the row)."""

    steps: list[str] = field(default_factory=list)
    fallbacks: list[str] = field(default_factory=list)

    def step(self, text: str) -> None:
        """Record a step that went as planned."""
        self.steps.append(text)

    def fallback(self, text: str) -> None:
        """Record a step the model's answer could not serve, and what stood in for it."""
        self.fallbacks.append(text)

    def text(self) -> str:
        """The account as the lines after the answer's JSON."""
        lines = [ACCOUNT_HEADER] + [f"- {s}" for s in self.steps]
        lines += [f"fallback: {f}" for f in self.fallbacks] or ["fallbacks: none"]
        return "\n".join(lines)


def _schema(properties: dict[str, Any]) -> dict[str, Any]:
    return {"type": "object", "required": list(properties), "properties": properties}


_DETECTIONS_SCHEMA = _schema(
    {
        "detections": {
            "type": "array",
            "items": _schema(
                {
                    "image": {"type": "integer", "minimum": 0},
                    "x": {"type": "number"},
                    "y": {"type": "number"},
                    "box": {"type": "array", "items": {"type": "number"}, "minItems": 4, "maxItems": 4},
                }
            ),
        }
    }
)


class GeometricStrategy(Strategy):
    """Ask the model to read the sentence and point; solve the geometry exactly.

    In a run it reads the frames' cameras (the release's ``exploration_log.json``); the
    GroundingAgent calls :meth:`solve_posed` with the robot's own cameras brought into the
    benchmark's world instead, and returns the solved 3D target as the goal.

    Options: ``max_tokens`` per sub-question (default 512), ``temperature`` (default: the
    backend's), ``min_ray_angle_deg`` (rays spanning less than this are not triangulated;
    default 4).
    """

    def __init__(self, max_tokens: int = 512, temperature: float | None = None, min_ray_angle_deg: float = MIN_RAY_ANGLE_DEG) -> None:
        if not isinstance(max_tokens, int) or isinstance(max_tokens, bool) or max_tokens < 1:
            raise ValueError(f"strategy option max_tokens must be a positive integer, got {max_tokens!r}")
        self.generation = generation_options(max_tokens, temperature)
        if not isinstance(min_ray_angle_deg, (int, float)) or not 0 <= min_ray_angle_deg < 90:
            raise ValueError(f"strategy option min_ray_angle_deg must be a number in [0, 90), got {min_ray_angle_deg!r}")
        self.min_ray_angle_deg = float(min_ray_angle_deg)

    # -- requests -----------------------------------------------------------------------------
    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """The final answer's spec: the paper's ``{selected_image, x, y}`` (A/B) or ``{x, y}`` (C)."""
        return answer_spec(instance)

    def _text_request(self, instance: Instance, text: str, schema: dict[str, Any], question: dict[str, Any]) -> Request:
        width, height = instance.frame_size
        spec = AnswerSpec(schema=schema, width=width, height=height, n_frames=1, asks_frame=False)
        return Request((Message("user", (TextPart(text),)),), spec, self.generation, instance=instance, question=question)

    def read_request(self, instance: Instance) -> Request:
        """Sub-question 1: observer (A/B), anchor and direction, read from the sentence."""
        types = ", ".join(known_types())
        directions = {"type": "string", "enum": list(DIRECTION_NAMES)}
        words = {"directions": ", ".join(DIRECTION_NAMES), "direction_choices": "|".join(DIRECTION_NAMES)}
        if instance.povbench_condition.uses_exploration_frames:
            text = render("geometric_read_frames", sentence=instance.sentence, types=types, **words)
            props = {"observer": {"type": "string"}, "anchor": {"type": "string"}, "direction": directions}
        else:
            text = render("geometric_read_given", sentence=instance.sentence, types=types, **words)
            props = {"anchor": {"type": "string"}, "direction": directions}
        return self._text_request(instance, text, _schema(props), {"kind": READ, "asks": list(props)})

    def surface_request(self, instance: Instance, anchor: str, direction: str, *, words: tuple[str, str] | None = None) -> Request:
        """Sub-question 2: what the target rests on. ``words`` (anchor, direction) replace the
        words made from ``anchor`` and ``direction`` (the planned turn's placeholders)."""
        anchor_words, direction_words = words or (object_words(anchor), _direction_words(direction))
        text = render("geometric_surface", sentence=instance.sentence, anchor=anchor_words, direction=direction_words)
        schema = _schema({"surface": {"type": "string", "enum": list(SURFACE_KINDS)}})
        return self._text_request(instance, text, schema, {"kind": SURFACE, "anchor": anchor, "direction": direction})

    def locate_request(self, instance: Instance, images: ImageStore, object_type: str, role: str, *, words: str | None = None) -> Request:
        """Sub-question 3: the object's centre and box in every shown frame where it is seen.
        ``words`` replace the object's name made from ``object_type`` (a planned turn's placeholder)."""
        width, height = instance.frame_size
        hashes = shown_images(instance, images)
        frames = instance.povbench_condition.uses_exploration_frames
        name = object_words(object_type) if words is None else words
        if frames:
            text = render("geometric_locate_frames", object=name, **frame_values(width, height, len(hashes)))
        else:
            text = render("geometric_locate_given", object=name, **frame_values(width, height))
        message = Message("user", (*image_parts(hashes, frames), TextPart(text)))
        spec = AnswerSpec(schema=_DETECTIONS_SCHEMA, width=width, height=height, n_frames=len(hashes), asks_frame=False)
        question = {"kind": LOCATE, "object": object_type, "role": role, "frames": len(hashes)}
        return Request((message,), spec, self.generation, instance=instance, question=question)

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """The first request: reading the sentence (the rest depend on its answer)."""
        return self.read_request(instance)

    def plan_turns(self, instance: Instance, images: ImageStore) -> list[PlannedTurn]:
        """The sub-questions in order, with placeholders for what turn 1's answer names, then
        the worked-out answer (never sent). A step whose earlier answer is unusable is skipped
        (the notes say when each is asked), so a run may make fewer requests than planned."""
        anchor, direction = earlier_answer(1, "anchor"), earlier_answer(1, "direction")
        turns = [
            PlannedTurn(self.read_request(instance)),
            PlannedTurn(self.surface_request(instance, anchor, direction, words=(anchor, direction)), note="asked when turn 1 names an anchor"),
            PlannedTurn(self.locate_request(instance, images, anchor, "anchor", words=anchor), note="asked when turn 1 names an anchor"),
        ]
        if instance.povbench_condition.uses_exploration_frames:
            observer = earlier_answer(1, "observer")
            turns.append(
                PlannedTurn(
                    self.locate_request(instance, images, observer, "observer", words=observer),
                    note="asked when turn 1 names the observer's furniture and turn 3 finds the anchor",
                )
            )
        turns.append(PlannedTurn(self.final_request(instance), sent=False, note="the answer, solved from the earlier answers"))
        return turns

    # -- the conversation ---------------------------------------------------------------------
    async def solve(
        self, instance: Instance, ask: Ask, images: ImageStore, *, speaker_at: Sequence[float] | np.ndarray | None = None
    ) -> list[tuple[Request, Response]]:
        """Ask the sub-questions, solve the geometry with the frames' cameras, and return every
        turn, the answer last. ``speaker_at``: see :meth:`solve_posed`."""
        return await self.solve_posed(instance, ask, images, [f.camera for f in instance.frames], speaker_at=speaker_at)

    async def solve_posed(
        self,
        instance: Instance,
        ask: Ask,
        images: ImageStore,
        cameras: Sequence[ViewCamera],
        *,
        speaker_at: Sequence[float] | np.ndarray | None = None,
    ) -> list[tuple[Request, Response]]:
        """:meth:`solve` with ``cameras`` (one per shown frame, describing the shown image, in
        the benchmark's world: y up, floor at ``y = 0``, left-handed) in place of the frames'.

        The target of A/B comes back in that world (``Response.solved_point``); C uses only the
        camera's field of view (the observer view has no pose). ``speaker_at`` (A/B): where the
        speaker stood, in that world, when it is known (a robot that saw the person; a training
        rationale that states it): the directions start from there, as the benchmark's start
        from the observer camera, and the observer's furniture is not asked for.
        """
        if len(cameras) != len(instance.frames):
            raise ValueError(f"solve_posed: {len(cameras)} cameras for {len(instance.frames)} frames")
        turns: list[tuple[Request, Response]] = []
        account = Account()

        async def exchange(request: Request) -> dict[str, Any] | None:
            response = await ask(request)
            turns.append((request, response))
            return json_object(response.text)

        read = await exchange(self.read_request(instance))
        anchor = normalize_type(read.get("anchor")) if read else None
        direction = normalize_direction(read.get("direction")) if read else None
        observer = normalize_type(read.get("observer")) if read and instance.povbench_condition.uses_exploration_frames else None
        if anchor is None:
            account.fallback("the anchor could not be read from the answer: no geometry is possible")
            return turns + [self._final(instance, None, account)]
        if direction is None:
            direction = FALLBACK_DIRECTION
            account.fallback(f"the direction could not be read from the answer: took '{FALLBACK_DIRECTION}'")
        account.step(f"read: anchor {anchor}, direction {direction}" + (f", observer {observer}" if observer else ""))

        answer = await exchange(self.surface_request(instance, anchor, direction))
        surface = answer.get("surface") if answer else None
        surface = surface.strip().lower() if isinstance(surface, str) else None
        if surface not in SURFACE_KINDS:
            surface = "anchor" if spec_of(direction).vertical else "floor"
            account.fallback(f"the surface could not be read from the answer: took '{surface}'")
        else:
            account.step(f"surface: {surface}")

        width, height = instance.frame_size
        n = len(instance.frames)
        anchor_seen, dropped = parse_detections(await exchange(self.locate_request(instance, images, anchor, "anchor")), n, width, height)
        if dropped:
            account.fallback(f"{dropped} anchor detection(s) unusable (frame out of range or repeated, or no point): left out")
        if not anchor_seen:
            account.fallback("the anchor was not found in any frame: no geometry is possible")
            return turns + [self._final(instance, None, account)]

        if not instance.povbench_condition.uses_exploration_frames:
            first = anchor_seen[0]
            sol = solve_given_view(direction, anchor, size_prior(anchor), first.pixel, first.box, surface, width, height, cameras[0].fov)
            how = "tilt fitted to the anchor's box" if sol.fitted else "no usable box: tilt guessed from the pointed centre"
            (account.step if sol.fitted else account.fallback)(f"observer view: {how} ({sol.tilt_deg:.1f} deg)")
            account.step(f"target: pixel ({sol.pixel[0]:.1f}, {sol.pixel[1]:.1f})" + ("" if sol.in_frame else ", outside the image: clamped"))
            return turns + [self._final(instance, (None, sol.pixel), account)]

        anchor_box = self.anchor_estimate(anchor, anchor_seen, cameras, account)
        observer_at = None
        if speaker_at is not None:
            observer_at = np.asarray(speaker_at, dtype=float)
            account.step(f"observer: where the speaker stood, given, at ({_xyz(observer_at)})")
        elif observer is None:
            account.fallback("the observer's furniture could not be read from the answer")
        else:
            seen, dropped = parse_detections(await exchange(self.locate_request(instance, images, observer, "observer")), n, width, height)
            if dropped:
                account.fallback(f"{dropped} observer detection(s) unusable: left out")
            estimate = locate([Sighting(cameras[d.frame], d.pixel) for d in seen], size_prior(observer).centre_height, self.min_ray_angle_deg)
            if estimate is None:
                account.fallback(f"the {observer} was not found in any frame")
            else:
                observer_at = np.asarray(estimate.point)
                account.step(f"observer: {_how_located(estimate)} at ({_xyz(observer_at)})")
        if observer_at is None:
            observer_at = np.mean([np.asarray(cameras[d.frame].position, dtype=float) for d in anchor_seen], axis=0)
            account.fallback("observer placed at the mean position of the cameras that saw the anchor")
        target = place_target(direction, anchor_box, anchor, observer_at, surface)
        choice = choose_frame(target, cameras)
        account.step(f"target: ({_xyz(target)}); frame {choice.index} ({choice.placement})")
        return turns + [self._final(instance, (choice.index, choice.pixel), account, target)]

    def anchor_estimate(self, anchor: str, seen: Sequence[Detection], cameras: Sequence[ViewCamera], account: Account | None = None) -> AnchorEstimate:
        """The anchor's box from its detections (at least one): centre located from the
        sightings, extent fitted to the outlines; the steps go into ``account`` when given."""
        account = account or Account()
        prior = size_prior(anchor)
        estimate = locate([Sighting(cameras[d.frame], d.pixel) for d in seen], prior.centre_height, self.min_ray_angle_deg)
        assert estimate is not None  # seen is not empty
        outlines = [Outline(cameras[d.frame], d.box) for d in seen if d.box is not None]
        sigma = TRIANGULATED_CENTRE_SIGMA if estimate.method == "triangulated" else PRIOR_CENTRE_SIGMA
        prior_half = (prior.size[0] / 2.0, prior.half_height, prior.size[2] / 2.0)
        box = fit_box(estimate.point, outlines, prior_half, sigma)
        account.step(f"anchor: {_how_located(estimate)} at ({_xyz(estimate.point)})")
        if box.edges_used:
            account.step(f"anchor box: {box.edges_used} box edges, half sizes ({_xyz(box.half)})")
        else:
            account.fallback(f"no usable anchor box edge: the {anchor}'s usual size stands in")
        return AnchorEstimate(box.centre, box.half)

    def final_request(self, instance: Instance) -> Request:
        """The final turn's request: it stands for the worked-out answer and is never sent."""
        return Request(
            (Message("user", (TextPart("(worked out by the geometric strategy; not sent to a model)"),)),),
            answer_spec(instance),
            self.generation,
            instance=instance,
            question={"kind": FINAL},
        )

    def _final(
        self, instance: Instance, answer: tuple[int | None, tuple[float, float]] | None, account: Account, target: Sequence[float] | np.ndarray | None = None
    ) -> tuple[Request, Response]:
        """The worked-out answer as the last turn (``by_strategy``): JSON, then the account.

        With a 3D target (A/B: in the world frame of the frames' cameras) the JSON also holds
        ``"target_3d": [x, y, z]``, which parsers ignore and the GroundingAgent returns as its goal.
        """
        width, height = instance.frame_size
        if answer is None:
            answer = (0, (width / 2.0, height / 2.0))
            account.fallback("answered the image centre" + (" of frame 0" if instance.povbench_condition.uses_exploration_frames else ""))
        frame, (x, y) = answer
        doc: dict[str, Any] = {"selected_image": frame} if instance.povbench_condition.uses_exploration_frames else {}
        doc |= {"x": round(float(x), 2), "y": round(float(y), 2)}
        if target is not None:
            doc[TARGET_3D] = [round(float(v), 4) for v in target]
        text = json.dumps(doc) + "\n" + account.text()
        request = self.final_request(instance)
        solved = tuple(float(v) for v in target) if target is not None else None
        return request, Response(text=text, model="geometric solver", by_strategy=True, solved_point=solved)  # type: ignore[arg-type]


def _direction_words(direction: str) -> str:
    spec = direction_spec(direction)
    return spec.short_words if spec is not None else direction


def _how_located(estimate) -> str:
    views = f"seen in {estimate.views} frame{'s' if estimate.views != 1 else ''}"
    if estimate.method == "triangulated":
        return f"{views}, triangulated (rays {estimate.spread_deg:.0f} deg apart)"
    return f"{views}, ray(s) met at its type's usual centre height"


def _xyz(p: Sequence[float] | np.ndarray) -> str:
    return ", ".join(f"{float(v):.2f}" for v in p)


@hookimpl
def register_strategies(register) -> None:
    """Contribute the geometric strategy."""
    register(
        "geometric",
        GeometricStrategy,
        description="Multi-turn: the model reads the sentence and points; the observer-relative geometry is solved exactly",
    )

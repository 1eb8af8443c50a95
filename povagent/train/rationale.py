"""Reasoning traces in the prompts' own steps, filled from an instance's scene facts.

``s-cot`` follows the Spatial-CoT prompt's steps (1 image, 2 observer, 3 anchor, 4a-4e spatial
reasoning, 5 conclusion); ``cot`` the CoT prompt's (its step 4 is one sentence); ``none`` is the
bare answer. Each step has a few phrasings picked by a generator seeded from (seed, instance id),
so the text varies across a set yet is the same on every export. Every number and word that
states a fact comes from :class:`~povagent.tasks.scene_facts.InstanceFacts`; the template adds nothing
the geometry does not say (the S-CoT step 4c inventory lists only what the scene records hold:
the anchor's box edges and the observer's furniture, not objects whose positions the release
lacks). The final line is the answer in the benchmark's JSON, as the prompt asks.
"""

from __future__ import annotations

import hashlib
import json
import random
from collections.abc import Sequence

from povagent.dataset.release_models import DIRECTIONS, Direction
from povagent.geometry.directions import spec_of
from povagent.tasks.scene_facts import InstanceFacts, PixelBox

RATIONALES = ("none", "cot", "s-cot")

#: The relation as a phrase before the anchor's name (the registry's paper wording).
RELATION_PHRASES: dict[Direction, str] = {d: spec_of(d).paper_words for d in DIRECTIONS}


def answer_json(facts: InstanceFacts, exact: bool = False) -> str:
    """The answer as the benchmark's prompt asks for it, e.g. ``{"selected_image": 3, "x": 231, "y": 340}``.

    ``exact`` writes the ground truth's pixel as a float (official L2 0 to rounding); otherwise
    whole pixels inside the frame, as the prompt's ``<integer 0-W-1>`` asks.
    """
    x, y = facts.answer_xy if exact else facts.answer_pixel()
    body: dict[str, float | int] = {}
    if facts.frame_index is not None:
        body["selected_image"] = facts.frame_index
    body["x"], body["y"] = x, y
    return json.dumps(body)


def _words(name: str) -> str:
    """``CoffeeTable`` -> ``coffee table``."""
    out: list[str] = []
    for ch in name:
        if ch.isupper() and out:
            out.append(" ")
        out.append(ch.lower())
    return "".join(out)


def _pick(rng: random.Random, options: Sequence[str]) -> str:
    return options[rng.randrange(len(options))]


def _xy(point: tuple[float, float]) -> str:
    return f"({round(point[0])}, {round(point[1])})"


def _rng(seed: int, instance_id: str) -> random.Random:
    digest = hashlib.sha256(f"{seed}\x00{instance_id}".encode()).digest()
    return random.Random(int.from_bytes(digest[:8], "big"))


def _step1(facts: InstanceFacts, rng: random.Random) -> str:
    obs, anc, k = _words(facts.observer_type), _words(facts.anchor_type), facts.frame_index
    if facts.observer_visible:
        return _pick(rng, (
            f"Image {k} shows both the {obs} the observer was working at and the {anc} named as the landmark.",
            f"The {obs} and the {anc} are both visible in Image {k}, so Image {k} is the best match.",
            f"Image {k} is the frame where the {obs} and the {anc} can both be seen.",
        ))
    return _pick(rng, (
        f"No frame shows the {obs} with the target in view, but Image {k} shows the {anc}; I select Image {k}.",
        f"Image {k} shows the {anc} with room around it for the target; the {obs} is out of this frame.",
    ))


def _side(column: str) -> str:
    """``left`` -> ``on the left side``; ``centre`` -> ``in the centre``."""
    return "in the centre" if column == "centre" else f"on the {column} side"


def stood_phrase(facts: InstanceFacts) -> str:
    """Where the speaker stood, from the camera: ``stood 0.85 m to the left of the camera and
    2.10 m ahead of it`` (metres on the floor, to the centimetre)."""
    right, ahead = (round(v, 2) for v in facts.speaker_offset)
    side = "right" if right >= 0 else "left"
    along = "ahead of" if ahead >= 0 else "behind"
    return f"stood {abs(right):.2f} m to the {side} of the camera and {abs(ahead):.2f} m {along} it"


def turned_phrase(facts: InstanceFacts) -> str:
    """The speaker's heading against the camera's: ``turned 35° to the right of the camera's heading``."""
    degrees = round(abs(facts.facing_deg))
    if degrees == 0:
        return "turned along the camera's heading"
    return f"turned {degrees}° to the {'right' if facts.facing_deg > 0 else 'left'} of the camera's heading"


def _step2(facts: InstanceFacts, rng: random.Random) -> str:
    obs, anc, k = _words(facts.observer_type), _words(facts.anchor_type), facts.frame_index
    if facts.observer_visible and facts.observer_xy is not None and facts.observer_column is not None:
        where = _pick(rng, (
            f"The {obs} is {_side(facts.observer_column)} of Image {k}, around {_xy(facts.observer_xy)}.",
            f"In Image {k} the {obs} appears {_side(facts.observer_column)}, near {_xy(facts.observer_xy)}.",
        ))
    else:
        where = f"The {obs} is not inside Image {k}."
    stood = _pick(rng, (
        f"Working at the {obs}, the speaker {stood_phrase(facts)}.",
        f"Seen from this camera, the speaker {stood_phrase(facts)}, at the {obs}.",
    ))
    looks = _pick(rng, (
        f"Facing the {anc} from there, the observer is {turned_phrase(facts)}: looking {facts.facing}.",
        f"From there the observer faces the {anc}, {turned_phrase(facts)}, so they look {facts.facing}.",
    ))
    return f"{where} {stood} {looks}"


def _span(box: PixelBox | None) -> str:
    return f", spanning x {box.x0}-{box.x1} and y {box.y0}-{box.y1}" if box is not None else ""


def _step3(facts: InstanceFacts, rng: random.Random) -> str:
    anc = _words(facts.anchor_type)
    span = _span(facts.anchor_box)
    here = _pick(rng, (
        f"The {anc} is centred near {_xy(facts.anchor_xy)}{span}.",
        f"The landmark, the {anc}, sits at about {_xy(facts.anchor_xy)}{span}.",
    ))
    if not facts.anchor_other_views:
        return here
    named = [f"Image {v.frame_index} near {_xy(v.xy)}{_span(v.box)}" for v in facts.anchor_other_views]
    views = named[0] if len(named) == 1 else "; ".join(named[:-1]) + "; and " + named[-1]
    return here + " " + _pick(rng, (f"It is also seen in {views}.", f"The same {anc} appears in {views}."))


def _target_sentence(facts: InstanceFacts, rng: random.Random) -> str:
    anc = _words(facts.anchor_type)
    phrase = RELATION_PHRASES[facts.direction]
    towards = (
        f"towards the {facts.image_direction} of the image" if facts.image_direction != "out of view" else "out of this view"
    )
    x, y = facts.answer_pixel()
    return _pick(rng, (
        f"The target is {phrase} the {anc}, {facts.surface}; from the observer's side that is {towards}, at about ({x}, {y}).",
        f"So the object rests {facts.surface}, {phrase} the {anc} as the observer sees it: {towards}, around ({x}, {y}).",
    ))


def s_cot_step4(facts: InstanceFacts, rng: random.Random) -> list[str]:
    """The S-CoT prompt's 4a-4e, filled from the facts."""
    anc, obs = _words(facts.anchor_type), _words(facts.observer_type)
    towards = f"the {facts.image_direction} of the image" if facts.image_direction != "out of view" else "out of this view"
    box = facts.anchor_box
    edges = (
        f"the {anc}'s left edge at x {box.x0}, right edge at x {box.x1}, top at y {box.y0}, bottom at y {box.y1}"
        if box is not None else f"the {anc}'s centre at {_xy(facts.anchor_xy)}"
    )
    inventory = edges
    if facts.observer_visible and facts.observer_xy is not None:
        inventory += f"; the {obs} (the observer's side) at {_xy(facts.observer_xy)}"
    x, y = facts.answer_pixel()
    return [
        f"4a) Facing the {anc} from the {obs}, {facts.relation} points towards {towards}.",
        f"4b) Anchor coordinate: {_xy(facts.anchor_xy)}.",
        f"4c) Reference points: {inventory}.",
        f"4d) The sentence places the target {facts.relation} relative to the {anc} ({facts.surface}).",
        f"4e) {_target_sentence(facts, rng).replace(f'at about ({x}, {y})', f'at about ({x}, {y}) in pixels')}",
    ]


def rationale_text(facts: InstanceFacts, kind: str, seed: int = 0, exact: bool = False) -> str:
    """The assistant's whole answer for ``facts``: the reasoning of ``kind``, then the JSON line.

    ``none`` (and every Given instance, whose benchmark prompt asks for the JSON alone) gives
    the JSON line only.
    """
    if kind not in RATIONALES:
        raise ValueError(f"rationale must be one of {', '.join(RATIONALES)}, not {kind!r}")
    answer = answer_json(facts, exact)
    if kind == "none" or facts.frame_index is None:
        return answer
    rng = _rng(seed, facts.instance_id)
    k = facts.frame_index
    x, y = facts.answer_pixel()
    if kind == "s-cot":
        step4 = "Step 4 — Spatial reasoning:\n" + "\n".join(s_cot_step4(facts, rng))
    else:
        step4 = f"Step 4 — Spatial reasoning: {_target_sentence(facts, rng)}"
    lines = [
        f"Step 1 — Image selection: {_step1(facts, rng)}",
        f"Step 2 — Observer position: {_step2(facts, rng)}",
        f"Step 3 — Anchor landmark: {_step3(facts, rng)}",
        step4,
        f"Step 5 — Conclusion: Image {k}, target at ({x}, {y}).",
        answer,
    ]
    return "\n\n".join(lines[:-1]) + "\n" + lines[-1]

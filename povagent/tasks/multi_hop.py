"""Multi-hop inference: the relation reached through an intermediate object.

What it is for: the second of the paper's future-work tasks. An instance chains two relations,
both from where the speaker stood: the target's relation to the anchor (the point task's, which
asks the observer to be grounded) and the anchor's relation to an intermediate object of the
same room, known exactly from the generated house's object boxes (:class:`Hop`). It is asked in
one of two ways:

* ``point`` (the official metric): the sentence names the anchor through the intermediate ("I
  saw the book to the left of the sofa that stood to the right of the lamp"); the answer is the
  point task's, scored against the same ground truth;
* ``choice``: the sentence, then the hop ("From where I stood, the lamp was to the left of the
  sofa."), then "From where the speaker stood, where is the book relative to the lamp?" over the
  registry's directions (shuffled per instance, as the relation task's).

An intermediate is kept only when the chain decides the answer and the geometry agrees: an
object standing on the anchor (the anchor's vertical direction) passes a beside-relation on
unchanged; an object wholly beside the anchor on one side passes on the mirror of that side to a
target on the far side or on top. The gold is then also what :func:`view_relation` reads from
the target's ground-truth point and the intermediate's box; a chain the geometry contradicts is
no instance. A (pair, direction) without such an intermediate has no multi-hop instance.

What it must not do: read a house's scene anywhere but its generated record (a house of the
public release has none: the task refuses it in one line).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.instances import Instance
from povagent.generate.scene import House, PlacedObject
from povagent.generate.sentences import OBJECT_NAMES, anchor_phrase, relation_phrase
from povagent.geometry.directions import DIRECTION_REGISTRY, spec_of
from povagent.geometry.ground_truth import direction_vectors
from povagent.tasks.relation import GIVEN_VIEW, direction_options, label_of
from povagent.tasks.sentence_parts import sentence_parts

#: Least clear gap (m) between two boxes, or a point and a box, for a relation to hold.
CLEARANCE = 0.05
#: Farthest an intermediate beside the anchor may stand from it (m): one glance takes in both.
MAX_GAP = 1.5


@dataclass(frozen=True)
class Hop:
    """The intermediate object, its relation to the anchor (``link``) and the target's relation
    to it (``gold``), all from the speaker's view."""

    intermediate: PlacedObject
    name: str
    link: str
    gold: str


def house_scene(dataset_root: Path, house_id: str) -> House:
    """The generated house's objects rebuilt from its record (refused in one line for a house
    this generator version did not make)."""
    from povagent.active.house import check_generated
    from povagent.generate.house_pipeline import furnished_house

    seed, index = check_generated(dataset_root, house_id)
    return furnished_house(seed, index)


def _half_extent(size: tuple[float, float, float], axis: np.ndarray) -> float:
    """Half the length of an axis-aligned box's xz footprint along a unit xz vector."""
    return abs(axis[0]) * size[0] / 2 + abs(axis[2]) * size[2] / 2


def view_relation(point: np.ndarray, box: PlacedObject, vectors: dict[str, np.ndarray]) -> str | None:
    """The one registry direction ``point`` stands in from ``box`` as the speaker sees it, or
    None when none or several hold.

    A beside direction holds when the point is clear of the box's footprint along its vector by
    :data:`CLEARANCE`, and every other is clearly short of it by as much (a point near an edge is
    none: where it is depends on a few centimetres); the vertical one when the point is above
    the box's top, over its footprint by as much."""
    offset = np.asarray(point, dtype=float) - np.asarray(box.center, dtype=float)
    beyond = {name: float(offset @ v) - _half_extent(box.size, v) for name, v in vectors.items()}
    if any(abs(excess) <= CLEARANCE for excess in beyond.values()):
        return None
    holding = [name for name, excess in beyond.items() if excess > 0]
    if len(holding) == 1:
        return holding[0]
    vertical = next(spec.name for spec in DIRECTION_REGISTRY if spec.vertical)
    over = all(abs(float(offset @ v)) < _half_extent(box.size, v) - CLEARANCE for v in vectors.values())
    return vertical if over and point[1] > box.top + CLEARANCE else None


def _beside(anchor: PlacedObject, other: PlacedObject, vectors: dict[str, np.ndarray]) -> str | None:
    """The lateral direction ``other`` stands in from ``anchor`` when its box is wholly on that
    side (a clear gap of at most :data:`MAX_GAP`) and level with it along the line of sight."""
    centre = np.asarray(other.center) - np.asarray(anchor.center)
    for spec in DIRECTION_REGISTRY:
        if not spec.lateral:
            continue
        v = vectors[spec.name]
        gap = float(centre @ v) - _half_extent(anchor.size, v) - _half_extent(other.size, v)
        along = next(vectors[s.name] for s in DIRECTION_REGISTRY if s.axis is not None and not s.lateral)
        level = abs(float(centre @ along)) < _half_extent(anchor.size, along) + _half_extent(other.size, along)
        if CLEARANCE <= gap <= MAX_GAP and level:
            return spec.name
    return None


def chained(link: str, direction: str) -> str | None:
    """The target's relation to the intermediate that the two relations decide, or None.

    On the anchor (``link`` vertical): a beside direction passes on unchanged. Beside it
    (``link`` lateral): a target on the far side (the mirror of ``link``) or on top is on that
    far side of the intermediate too."""
    hop, asked = spec_of(link), spec_of(direction)
    if hop.vertical:
        return None if asked.vertical else direction
    if hop.lateral and (asked.vertical or direction == hop.mirror):
        return hop.mirror
    return None


def _rng(key: str) -> np.random.Generator:
    return np.random.default_rng(int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "big"))


def find_hop(instance: Instance, house: House) -> Hop | None:
    """The intermediate of an instance (the same for its three conditions), or None."""
    anchor_id, observer_id = instance.anchor_object.objectId, instance.observer_object.objectId
    try:
        anchor = house.by_id(anchor_id)
    except KeyError:
        return None
    vectors = direction_vectors(np.asarray(anchor.center), np.asarray(instance.observer_camera.position))
    target = np.asarray(instance.target)
    vertical = next(spec.name for spec in DIRECTION_REGISTRY if spec.vertical)
    key = f"{instance.house_id}/{instance.pair_id}/{instance.direction}"
    found: list[tuple[PlacedObject, str, str]] = []
    for other in sorted(house.objects, key=lambda o: o.object_id):
        if other.object_id in (anchor_id, observer_id) or other.object_type == anchor.object_type:
            continue
        if other.object_type not in OBJECT_NAMES or other.room_id != anchor.room_id:
            continue
        link = vertical if other.support == anchor_id else _beside(anchor, other, vectors)
        gold = chained(link, str(instance.direction)) if link is not None else None
        if gold is not None and link is not None and view_relation(target, other, vectors) == gold:
            found.append((other, link, gold))
    rng = _rng(key)
    while found:
        other, link, gold = found.pop(int(rng.integers(len(found))))
        name = anchor_phrase(house, other, rng)
        if name is not None:
            return Hop(other, name, link, gold)
    return None


def hop_sentence(hop: Hop, anchor_type: str, anchor_name: str) -> str:
    """ "From where I stood, the lamp was to the left of the sofa." (the anchor named as the
    sentence names it)."""
    return f"From where I stood, the {hop.name} was {relation_phrase(hop.link, anchor_type, anchor_name, False)}."


def anchor_through(hop: Hop, anchor_name: str) -> str:
    """The anchor named through the intermediate: "sofa that stood to the right of the lamp",
    "side table that the lamp stood on"."""
    link = spec_of(hop.link)
    if link.vertical:
        return f"{anchor_name} that the {hop.name} stood on"
    return f"{anchor_name} that stood {spec_of(link.mirror).paper_words} the {hop.name}"


def multi_hop_instance(instance: Instance, hop: Hop, answer: str) -> Instance:
    """The point instance asked through ``hop``: as a point (same ground truth) or a choice."""
    parts = sentence_parts(instance.sentence, str(instance.direction))
    anchor_type = instance.anchor_object.object_type
    if answer == "point":
        return replace(instance, sentence=parts.with_anchor(anchor_through(hop, parts.anchor)))
    lead = instance.sentence if instance.povbench_condition.uses_exploration_frames else f"{GIVEN_VIEW} {instance.sentence}"
    text = f"{lead} {hop_sentence(hop, anchor_type, parts.anchor)} From where the speaker stood, where is the {parts.target} relative to the {hop.name}?"
    options = direction_options(instance.id)
    question = ChoiceQuestion(question=text, options=options, gold=label_of(options, hop.gold), category=hop.gold, profile="plain")
    return replace(instance, sentence=text, question=question)

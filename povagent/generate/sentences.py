"""Query sentences for the three conditions: A Inferred, B Stated, C Given.

What it is for: stages 5 and 6 of the paper. Each observer object has activities a person does
with it; condition A describes only the activity ("While replacing the bulb, ..."), B the same
activity naming the object ("While replacing the light bulb on the floor lamp, ..."), C only the
relation ("The book was to the left of the bed."). Objects are named with natural variants
(couch or sofa, TV or television) that never leave the referenced type ambiguous. Targets are
drawn from the paper's surface-specific pools (its appendix table). What it must not do: judge
surfaces or compute positions.
"""

from __future__ import annotations

import re

import numpy as np

from povagent.generate.scene import House, PlacedObject
from povagent.geometry.directions import spec_of
from povagent.geometry.ground_truth import surface_names_anchor

#: The paper's target pools per supporting surface (appendix table), by AI2-THOR type.
TARGET_POOLS: dict[str, tuple[str, ...]] = {
    "Floor": ("Cloth", "Boots", "BasketBall", "BaseballBat", "Dumbbell", "DogBed"),
    "ArmChair": ("Book", "TeddyBear", "Cloth", "TissueBox", "Newspaper", "Mug", "Cup", "CellPhone", "RemoteControl", "Watch"),
    "Bed": ("Book", "Pillow", "TeddyBear", "Cloth", "TissueBox", "Newspaper", "CellPhone", "RemoteControl", "Watch"),
    "Chair": ("Cloth", "Book", "Pen", "Pencil", "CellPhone", "KeyChain", "Watch"),
    "CoffeeTable": ("Book", "TissueBox", "Newspaper", "Mug", "Cup", "Bottle", "RemoteControl", "CellPhone", "Watch", "KeyChain"),
    "CounterTop": ("Mug", "Cup", "Bottle", "Plate", "Bowl", "Fork", "Spoon", "Knife", "TissueBox"),
    "Desk": ("Book", "TissueBox", "Newspaper", "Mug", "Cup", "Pen", "Pencil", "CellPhone", "Watch", "KeyChain"),
    "DiningTable": ("Plate", "Bowl", "Fork", "Spoon", "Knife", "Mug", "Cup", "Bottle", "TissueBox", "Cloth", "KeyChain", "Watch"),
    "Dresser": ("Cloth", "Watch", "KeyChain", "CellPhone", "Book", "TissueBox"),
    "Microwave": ("Plate", "Bowl", "Mug", "Cup", "Fork", "Spoon", "Newspaper", "Watch", "KeyChain"),
    "ShelvingUnit": ("Book", "TeddyBear", "TissueBox", "Newspaper", "Cloth"),
    "SideTable": ("Book", "TissueBox", "Mug", "Cup", "CellPhone", "Watch", "RemoteControl", "KeyChain"),
    "Sofa": ("Book", "Pillow", "TeddyBear", "Cloth", "TissueBox", "Newspaper", "Mug", "Cup", "CellPhone", "RemoteControl", "Watch"),
    "Television": ("RemoteControl", "CellPhone", "TeddyBear", "Cloth", "TissueBox"),
    "Toilet": ("TissueBox", "Book", "Newspaper", "CellPhone"),
    # The paper calls its table "examples"; these surfaces occur here too and get pools in the
    # same spirit (small objects a person would leave there).
    "Fridge": ("Bottle", "Bowl", "TissueBox", "Book"),
    "WashingMachine": ("Cloth", "TissueBox", "Bottle"),
    "ClothesDryer": ("Cloth", "TissueBox", "Bottle"),
    "Safe": ("Book", "Watch", "KeyChain", "CellPhone"),
    "Stool": ("Book", "Cloth", "CellPhone", "Newspaper"),
    "Sink": ("Cloth", "TissueBox", "CellPhone"),
}

#: How a target type reads in a sentence (variants are equally natural).
TARGET_WORDS: dict[str, tuple[str, ...]] = {
    "BasketBall": ("basketball",),
    "BaseballBat": ("baseball bat",),
    "CellPhone": ("cell phone", "phone"),
    "RemoteControl": ("remote control", "remote"),
    "KeyChain": ("key chain", "keys"),
    "TissueBox": ("tissue box", "box of tissues"),
    "TeddyBear": ("teddy bear",),
    "DogBed": ("dog bed",),
    "Cloth": ("cloth", "rag"),
    "Boots": ("boots",),
}

#: Names of object types; the first is the plain one. Every variant names only that type.
OBJECT_NAMES: dict[str, tuple[str, ...]] = {
    "ArmChair": ("armchair",),
    "Bed": ("bed",),
    "Chair": ("chair",),
    "ClothesDryer": ("dryer", "clothes dryer"),
    "CoffeeMachine": ("coffee machine", "coffee maker"),
    "CoffeeTable": ("coffee table",),
    "CounterTop": ("counter", "countertop", "kitchen counter"),
    "Desk": ("desk",),
    "DeskLamp": ("desk lamp",),
    "Desktop": ("computer", "desktop computer"),
    "DiningTable": ("dining table",),
    "Doorway": ("doorway",),
    "Dresser": ("dresser", "chest of drawers"),
    "Faucet": ("faucet", "tap"),
    "FloorLamp": ("floor lamp", "standing lamp"),
    "Fridge": ("fridge", "refrigerator"),
    "GarbageCan": ("trash can", "garbage can"),
    "HandTowelHolder": ("hand towel holder", "hand towel ring"),
    "HousePlant": ("plant", "potted plant", "houseplant"),
    "Microwave": ("microwave",),
    "Safe": ("safe",),
    "ShelvingUnit": ("shelving unit", "bookshelf"),
    "SideTable": ("side table",),
    "Sink": ("sink",),
    "Sofa": ("sofa", "couch"),
    "Stool": ("stool",),
    "Television": ("TV", "television"),
    "Toaster": ("toaster",),
    "Toilet": ("toilet",),
    "TowelHolder": ("towel rack", "towel holder"),
    "WashingMachine": ("washing machine", "washer"),
}

#: Activities per observer type: (A, B). A never names the object; B names it as ``{obj}``.
#: A key ``Type@RoomType`` overrides the type's list in that room.
ACTIVITIES: dict[str, tuple[tuple[str, str], ...]] = {
    # Laid out by hand (the formatter is told to skip it): a table, one pair per line with each
    # type's pairs aligned under one another, so A and B read side by side.
    "ArmChair": (("reading a novel with a cup of tea", "reading a novel in the {obj} with a cup of tea"),
                 ("resting my feet after work", "resting in the {obj} after work")),
    "Bed": (("changing the sheets", "changing the sheets on the {obj}"),
            ("getting dressed in the morning", "sitting on the edge of the {obj} getting dressed"),
            ("reading before falling asleep", "reading in {obj} before falling asleep")),
    "Chair": (("eating my lunch", "sitting on the {obj} eating my lunch"),
              ("tying my shoelaces", "sitting on the {obj} tying my shoelaces")),
    "ClothesDryer": (("folding the warm laundry", "unloading the warm laundry from the {obj}"),),
    "CoffeeMachine": (("brewing my morning espresso", "brewing an espresso at the {obj}"),
                      ("waiting for my coffee to finish", "waiting for the {obj} to finish")),
    "CoffeeTable": (("doing a jigsaw puzzle", "doing a jigsaw puzzle on the {obj}"),
                    ("setting down the snacks for movie night", "setting the snacks on the {obj}")),
    "CounterTop": (("chopping vegetables for dinner", "chopping vegetables on the {obj}"),
                   ("kneading dough for bread", "kneading dough on the {obj}")),
    "Desk": (("answering my emails", "answering my emails at the {obj}"),
             ("doing my homework", "doing my homework at the {obj}")),
    "DeskLamp": (("switching on the light to read", "switching on the {obj}"),
                 ("adjusting the light over my notes", "adjusting the {obj} over my notes")),
    "Desktop": (("typing up a report", "typing up a report on the {obj}"),
                ("video-calling my sister", "video-calling my sister on the {obj}")),
    "DiningTable": (("eating dinner with my family", "eating dinner at the {obj}"),
                    ("setting out the plates", "setting the plates out on the {obj}")),
    "Doorway": (("calling the kids in for dinner", "standing in the {obj} calling the kids in for dinner"),
                ("saying goodbye to a guest", "saying goodbye to a guest at the {obj}")),
    "Dresser": (("picking out a pair of socks", "picking out socks from the {obj}"),
                ("putting away the folded clothes", "putting folded clothes away in the {obj}")),
    "Faucet": (("filling a glass of water", "filling a glass of water at the {obj}"),
               ("rinsing out a cup", "rinsing a cup under the {obj}")),
    "FloorLamp": (("replacing the bulb", "replacing the light bulb on the {obj}"),
                  ("turning on the reading light", "turning on the {obj}")),
    "Fridge": (("looking for something to eat", "looking in the {obj} for something to eat"),
               ("putting the groceries away", "putting the groceries in the {obj}")),
    "GarbageCan": (("taking out the trash", "emptying the {obj}"),
                   ("throwing away a wrapper", "throwing a wrapper into the {obj}")),
    "HandTowelHolder": (("drying my hands", "drying my hands on the towel at the {obj}"),
                        ("hanging up a fresh hand towel", "hanging a fresh towel on the {obj}")),
    "HousePlant": (("watering the greenery", "watering the {obj}"),
                   ("trimming off the dead leaves", "trimming the dead leaves off the {obj}")),
    "Microwave": (("reheating my leftovers", "reheating my leftovers in the {obj}"),
                  ("making popcorn", "making popcorn in the {obj}")),
    "Safe": (("locking away my passport", "locking my passport in the {obj}"),
             ("entering the combination", "entering the combination on the {obj}")),
    "ShelvingUnit": (("looking for a book to read", "browsing the {obj} for a book"),
                     ("dusting the shelves", "dusting the {obj}")),
    "SideTable": (("charging my phone", "charging my phone on the {obj}"),
                  ("setting down my glass of water", "setting my glass of water on the {obj}")),
    "Sink": (("washing dishes", "washing dishes at the {obj}"),
             ("scrubbing a pot", "scrubbing a pot in the {obj}")),
    "Sink@Bathroom": (("washing my hands", "washing my hands at the {obj}"),
                      ("brushing my teeth", "brushing my teeth at the {obj}")),
    "Sofa": (("watching a movie", "watching a movie from the {obj}"),
             ("taking an afternoon nap", "taking a nap on the {obj}")),
    "Stool": (("having a quick breakfast", "sitting on the {obj} having a quick breakfast"),
              ("reaching for the top cabinet", "standing on the {obj} to reach the top cabinet")),
    "Television": (("changing the channel", "changing the channel on the {obj}"),
                   ("wiping the dust off the screen", "wiping the dust off the {obj} screen")),
    "Toaster": (("making toast", "making toast in the {obj}"),
                ("waiting for the bread to pop up", "waiting for the {obj} to pop")),
    "Toilet": (("cleaning the bowl", "cleaning the {obj}"),
               ("replacing the paper roll", "replacing the paper roll next to the {obj}")),
    "TowelHolder": (("hanging up my towel after a shower", "hanging my towel on the {obj} after a shower"),
                    ("grabbing a fresh bath towel", "grabbing a fresh bath towel from the {obj}")),
    "WashingMachine": (("loading the laundry", "loading the laundry into the {obj}"),
                       ("starting a wash cycle", "starting a wash cycle on the {obj}")),
}  # fmt: skip

#: Sentence frames: the activity clause, the sighting verb, the target and the relation.
_FRAMES = (
    "While {act}, I {verb} the {target} {rel}.",  # the paper's own examples
    "While I was {act}, I {verb} the {target} {rel}.",
    "When I was {act}, I {verb} the {target} {rel}.",
    "I was {act} when I {verb} the {target} {rel}.",
)
#: The verbs of sighting the target ("I saw the book ...").
SIGHTING_VERBS = ("saw", "spotted", "noticed")
#: Anchors one sits or lies on: a target "up" is on them rather than "on top of" them.
_SEATS = frozenset({"Sofa", "ArmChair", "Bed", "Chair", "Stool"})

_PLURALS = frozenset({"boots", "keys"})

ROOM_WORDS = {"Kitchen": "kitchen", "LivingRoom": "living room", "Bedroom": "bedroom", "Bathroom": "bathroom"}


def _choice(rng: np.random.Generator, options):
    return options[int(rng.integers(len(options)))]


def word_for(object_type: str) -> str:
    """Default lower-case words of a type: ``TeddyBear`` -> ``teddy bear``."""
    return " ".join(w.lower() for w in re.findall(r"[A-Z][a-z]*", object_type))


def target_pool(surface: str, anchor: PlacedObject, house: House) -> tuple[str, tuple[str, ...]]:
    """(pool name, candidates) for a surface phrase: floor, the anchor itself, or its receptacle."""
    if "floor" in surface:
        return "Floor", TARGET_POOLS["Floor"]
    if anchor.object_type in TARGET_POOLS and _names(surface, anchor.object_type):
        return anchor.object_type, TARGET_POOLS[anchor.object_type]
    if anchor.support not in ("floor", "wall"):
        holder = house.by_id(anchor.support).object_type
        if holder in TARGET_POOLS:
            return holder, TARGET_POOLS[holder]
    return "Floor", TARGET_POOLS["Floor"]


def _names(surface: str, object_type: str) -> bool:
    """True when a surface phrase names ``object_type``: by the scorer's keywords or by any of
    the type's names (a judge may say "on the bookshelf" for a ShelvingUnit)."""
    text = surface.lower()
    return surface_names_anchor(text, object_type) or any(
        re.search(rf"\b{re.escape(n.lower())}\b", text) for n in OBJECT_NAMES.get(object_type, ())
    )


def anchor_phrase(house: House, anchor: PlacedObject, rng: np.random.Generator) -> str | None:
    """How to name the anchor so that only it fits; None when no name would be unambiguous.

    A type unique in the house is named plainly; a type unique within its room type is named
    with the room ("the side table in the bedroom"). A doorway belongs to two rooms, so it is
    named by them ("the doorway between the kitchen and the living room"), or as the front door.
    """
    if anchor.object_type == "Doorway":
        return _doorway_phrase(house, anchor, rng)
    name = _choice(rng, OBJECT_NAMES[anchor.object_type])
    if house.count_of_type(anchor.object_type) == 1:
        return name
    room_type = house.plan.rooms[anchor.room_id].room_type
    same = [o for o in house.objects if o.object_type == anchor.object_type and house.plan.rooms[o.room_id].room_type == room_type]
    if len(same) == 1:
        return f"{name} in the {ROOM_WORDS[room_type]}"
    return None


#: Names of the house's entrance (a Doorway with a door in it).
ENTRANCE_NAMES = ("front door", "entrance")


def _doorway_phrase(house: House, anchor: PlacedObject, rng: np.random.Generator) -> str | None:
    """A doorway named by where it is: the front door, or the two room types it joins (None
    when another doorway joins the same two room types)."""
    if "entrance" in anchor.flags:
        return _choice(rng, ENTRANCE_NAMES)

    def joined(o) -> tuple[str, ...]:
        return tuple(sorted(house.plan.rooms[r].room_type for r in o.rooms if r is not None))

    opening = min(
        (o for o in house.plan.openings if not o.is_entrance),
        key=lambda o: abs(o.center[0] - anchor.center[0]) + abs(o.center[1] - anchor.center[2]),
    )
    types = joined(opening)
    if len(set(types)) < 2 or sum(joined(o) == types for o in house.plan.openings) != 1:
        return None
    first, second = (ROOM_WORDS[t] for t in (types if rng.random() < 0.5 else types[::-1]))
    return f"doorway between the {first} and the {second}"


def relation_phrase(direction: str, anchor_type: str, anchor_name: str, on_anchor: bool) -> str:
    """``to the left of the bed``, ``on the left side of the counter``, ``on top of the fridge``:
    the registry's phrases of ``direction`` (its seat phrase for an anchor one sits on, its
    on-anchor phrase when the target stands on the anchor)."""
    spec = spec_of(direction)
    phrase = spec.sentence_phrase
    if spec.seat_phrase is not None and anchor_type in _SEATS:
        phrase = spec.seat_phrase
    elif on_anchor and spec.on_anchor_phrase is not None:
        phrase = spec.on_anchor_phrase
    return phrase.format(anchor=anchor_name)


def activity(observer: PlacedObject, house: House, rng: np.random.Generator) -> tuple[str, str]:
    """An (A, B) activity pair for the observer, B naming it with a natural variant."""
    room_type = house.plan.rooms[observer.room_id].room_type
    options = ACTIVITIES.get(f"{observer.object_type}@{room_type}", ACTIVITIES[observer.object_type])
    a, b = _choice(rng, options)
    return a, b.format(obj=_choice(rng, OBJECT_NAMES[observer.object_type]))


def sentences(
    observer: PlacedObject,
    anchor_type: str,
    anchor_name: str,
    direction: str,
    target_type: str,
    on_anchor: bool,
    house: House,
    rng: np.random.Generator,
) -> tuple[str, str, str]:
    """The A (Inferred), B (Stated) and C (Given) sentences of one (pair, direction)."""
    target = _choice(rng, TARGET_WORDS.get(target_type, (word_for(target_type),)))
    rel = relation_phrase(direction, anchor_type, anchor_name, on_anchor)
    act_a, act_b = activity(observer, house, rng)
    frame = _choice(rng, _FRAMES)
    verb = _choice(rng, SIGHTING_VERBS)
    a = frame.format(act=act_a, verb=verb, target=target, rel=rel)
    b = frame.format(act=act_b, verb=verb, target=target, rel=rel)
    c = f"The {target} {'were' if target in _PLURALS else 'was'} {rel}."
    return a, b, c

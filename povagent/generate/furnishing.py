"""Furniture placement: which of the 31 categories go in which room, and where.

What it is for: turn a floor plan into a furnished house following ProcTHOR's habits (its
placement annotations say which room types hold which objects) and the rules a person would
expect: sofas, beds, dressers and counters against walls; a TV on a stand facing the sofa with
a coffee table between them; chairs drawn up to the dining table or desk; lamps, microwaves and
faucets standing on their receptacles; towel holders on bathroom walls; doorways kept clear.
Sizes are the real ProcTHOR asset sizes. What it must not do: build meshes or render.

Every random choice comes from the ``numpy.random.Generator`` passed in, in a fixed order, so a
seed gives the same house every time.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from povagent.generate.assets import asset_database, choose_asset
from povagent.generate.floorplan import FloorPlan, Opening, Rect
from povagent.generate.room_layout import OPPOSITE, RoomLayout
from povagent.generate.scene import PlacedObject, object_id_for

#: Doorway objects: a frame around the opening, as thick as the wall plus its trim.
DOOR_FRAME_TRIM = 0.06


def doorway_object(o: Opening, index: int) -> PlacedObject:
    """The Doorway object of an opening: its frame, as wide as the opening plus the jambs."""
    cx, cz = o.center
    spec = next((a for a in asset_database()["Doorway"] if a.asset_id == o.asset_id), None)
    depth = 0.1 + 2 * 0.02
    size = (round(o.width + 2 * DOOR_FRAME_TRIM, 4), round(2.1 + DOOR_FRAME_TRIM, 4), depth)
    yaw = 0 if o.axis == "z" else 90
    center = (round(cx, 4), round(size[1] / 2, 4), round(cz, 4))
    return PlacedObject(
        object_id=object_id_for("Doorway", center),
        object_type="Doorway",
        asset_id=spec.asset_id if spec else o.asset_id,
        center=center,
        local_size=size,
        yaw=yaw,
        room_id=o.rooms[0],
        support="wall",
        style=index,
        flags=("entrance",) if o.is_entrance else (),
    )


# -- recipes ------------------------------------------------------------------------------------
def _maybe(rng: np.random.Generator, p: float) -> bool:
    return bool(rng.random() < p)


def _living_room(L: RoomLayout) -> None:
    rng = L.rng
    sofa = L.against_wall("Sofa", prefer="center", avoid_door_walls=True, access_depth=1.4,
                          fits=lambda a: a.width <= 2.6 and a.depth <= 1.1)
    if sofa is None:  # a room cut up by doorways: the smallest sofa, less floor kept in front
        sofa = L.against_wall("Sofa", access_depth=0.9, largest=False,
                              fits=lambda a: a.width <= 2.0 and a.depth <= 1.0)
    if sofa is not None:
        side_of = {0: "south", 180: "north", 90: "west", 270: "east"}[sofa.yaw]
        along = sofa.center[0] if sofa.yaw in (0, 180) else sofa.center[2]
        # the TV stands on a low dresser on the opposite wall, facing the sofa
        stand = L.against_wall("Dresser", sides=[OPPOSITE[side_of]], near=along, access_depth=0.8,
                               fits=lambda a: a.height <= 0.85 and a.width >= 1.0 and a.depth <= 0.6)
        if stand is not None:
            L.on_top(stand, "Television", near=0.0, fits=lambda a: a.height <= 0.95 and a.depth <= 0.45)
        _coffee_table(L, sofa)
        _beside(L, sofa, "SideTable", lamp_p=0.6)
        if _maybe(rng, 0.6):
            _beside(L, sofa, "FloorLamp", lamp_p=0.0)
    if _maybe(rng, 0.5):
        L.against_wall("ShelvingUnit", access_depth=0.6, fits=lambda a: a.depth <= 0.5)
    if _maybe(rng, 0.25):
        _dining_set(L)
    for kind, p in (("HousePlant", 0.6), ("GarbageCan", 0.4), ("Safe", 0.1)):
        if _maybe(rng, p):
            L.against_wall(kind, prefer="corner", access_depth=0.0)


def _coffee_table(L: RoomLayout, sofa: PlacedObject) -> None:
    spec = choose_asset("CoffeeTable", L.rng, lambda a: a.width <= sofa.local_size[0] and a.depth <= 0.8)
    if spec is None:
        return
    gap = 0.4
    f = sofa.front
    dist = sofa.local_size[2] / 2 + gap + spec.depth / 2
    table = L.free_standing("CoffeeTable", spec, sofa.center[0] + f[0] * dist, sofa.center[2] + f[2] * dist, sofa.yaw)
    if table is None or not _maybe(L.rng, 0.6):
        return
    # an armchair at one end of the coffee table, turned towards it
    chair = choose_asset("ArmChair", L.rng, lambda a: a.width <= 1.1)
    if chair is None:
        return
    side = np.array([f[2], 0.0, -f[0]]) * (1 if _maybe(L.rng, 0.5) else -1)
    dist = spec.width / 2 + 0.35 + chair.depth / 2
    yaw = int(round(np.degrees(np.arctan2(-side[0], -side[2])))) % 360
    L.free_standing("ArmChair", chair, table.center[0] + side[0] * dist, table.center[2] + side[2] * dist, yaw)


def _beside(L: RoomLayout, anchor: PlacedObject, object_type: str, lamp_p: float) -> PlacedObject | None:
    """Stand an object against the same wall as ``anchor``, just past one of its ends."""
    spec = choose_asset(object_type, L.rng, lambda a: a.depth <= 0.7 and a.width <= 0.8)
    if spec is None:
        return None
    side_name = {0: "south", 180: "north", 90: "west", 270: "east"}[anchor.yaw]
    along = anchor.center[0] if anchor.yaw in (0, 180) else anchor.center[2]
    half = anchor.local_size[0] / 2 + spec.width / 2 + 0.05
    ends = [along - half, along + half]
    if _maybe(L.rng, 0.5):
        ends.reverse()
    for t in ends:
        side = L.sides()[side_name]
        body = side.footprint(t, spec.width, spec.depth)
        if L.free(body):
            cx, cz = body.center
            obj = L.add(L.make(object_type, spec, (cx, spec.height / 2, cz), side.yaw))
            if lamp_p and _maybe(L.rng, lamp_p):
                L.on_top(obj, "DeskLamp", near=0.0, fits=lambda a: a.height <= 0.6)
            return obj
    return None


def _dining_set(L: RoomLayout) -> None:
    """A dining table in open floor with 2 to 4 chairs drawn up to it, facing it.

    Tables are tried in a seeded order, each along and across the room, at the free spot
    nearest the room's centre; the floor reserved around it is what its chairs need (a chair's
    depth and room to pull it out on the sides that get one, a narrow passage elsewhere).
    """
    rng = L.rng
    chair = choose_asset("Chair", rng, lambda a: a.height <= 1.05 and a.depth <= 0.6)
    tables = [a for a in asset_database()["DiningTable"] if a.width <= 1.8 and a.depth <= 1.1 and a.height <= 0.85]
    if chair is None or not tables:
        return
    n = int(rng.integers(2, 5))
    r = L.room.interior
    cx, cz = r.center
    for k in rng.permutation(len(tables)):
        spec = tables[int(k)]
        for yaw in ((0, 90) if rng.random() < 0.5 else (90, 0)):
            sx, sz = (spec.width, spec.depth) if yaw == 0 else (spec.depth, spec.width)
            # chairs go on the long sides first, then at the ends
            long_sides = [(0.0, 1.0), (0.0, -1.0)] if sx >= sz else [(1.0, 0.0), (-1.0, 0.0)]
            ends = [(1.0, 0.0), (-1.0, 0.0)] if sx >= sz else [(0.0, 1.0), (0.0, -1.0)]
            seats = (long_sides + ends)[:n]
            pull = chair.depth + 0.15
            grow = {s: (pull if s in seats else 0.3) for s in long_sides + ends}
            x0m, x1m, z0m, z1m = grow[(-1.0, 0.0)], grow[(1.0, 0.0)], grow[(0.0, -1.0)], grow[(0.0, 1.0)]
            xs = np.arange(r.x0 + sx / 2 + x0m, r.x1 - sx / 2 - x1m + 1e-6, 0.25)
            zs = np.arange(r.z0 + sz / 2 + z0m, r.z1 - sz / 2 - z1m + 1e-6, 0.25)
            spots = sorted(
                ((float(x), float(z)) for x in xs for z in zs),
                key=lambda q: (q[0] - cx) ** 2 + (q[1] - cz) ** 2,
            )
            for x, z in spots:
                reserve = Rect(x - sx / 2 - x0m, z - sz / 2 - z0m, x + sx / 2 + x1m, z + sz / 2 + z1m)
                if not L.free(reserve):
                    continue
                table = L.free_standing("DiningTable", spec, x, z, yaw)
                if table is None:
                    continue
                for dx, dz in seats:
                    reach = (sz if dz else sx) / 2 + chair.depth / 2 + 0.05
                    chair_yaw = int(round(np.degrees(np.arctan2(-dx, -dz)))) % 360
                    L.free_standing("Chair", chair, x + dx * reach, z + dz * reach, chair_yaw)
                return
    # a room too narrow for chairs all round (a galley kitchen): the table's long side goes
    # against a wall and the chairs stand along its open side
    table = L.against_wall("DiningTable", access_depth=chair.depth + 0.15, avoid_door_walls=True,
                           fits=lambda a: a.width <= 1.8 and a.depth <= 1.1 and a.height <= 0.85)
    if table is None:
        return
    f, w = table.front, table.local_size[0]
    across = np.array([f[2], 0.0, -f[0]])
    reach = table.local_size[2] / 2 + chair.depth / 2 + 0.05
    offsets = (-w / 4, w / 4) if w >= 2.2 * chair.width else (0.0,)
    for t in offsets[: max(1, n - 1)]:
        x, z = table.center[0] + f[0] * reach + across[0] * t, table.center[2] + f[2] * reach + across[2] * t
        L.free_standing("Chair", chair, x, z, table.yaw + 180)


def _kitchen(L: RoomLayout) -> None:
    rng = L.rng
    counter = L.against_wall("CounterTop", largest=True, avoid_door_walls=True, prefer="corner",
                             access_depth=0.9, fits=lambda a: a.asset_id.startswith("Countertop_I") and a.width >= 1.2)
    if counter is not None:
        sink = L.on_top(counter, "Sink", near=0.0, back_gap=0.08, sink_into=0.12,
                        fits=lambda a: a.height <= 0.25 and a.depth <= 0.5)
        if sink is not None:
            c_along = _along(counter, sink)
            L.on_top(counter, "Faucet", near=c_along, back_gap=0.0, fits=lambda a: a.height <= 0.4 and a.depth <= 0.12)
            L.top_use[counter.object_id].pop()  # the faucet sits behind the sink, not beside it
        for kind, p in (("Microwave", 0.8), ("Toaster", 0.7), ("CoffeeMachine", 0.6)):
            if _maybe(rng, p):
                L.on_top(counter, kind)
        side_name = {0: "south", 180: "north", 90: "west", 270: "east"}[counter.yaw]
        along = counter.center[0] if counter.yaw in (0, 180) else counter.center[2]
        fridge = L.against_wall("Fridge", sides=[side_name], near=along, access_depth=0.9,
                                fits=lambda a: a.width <= 1.0)
        if fridge is None:
            L.against_wall("Fridge", prefer="corner", access_depth=0.9, fits=lambda a: a.width <= 1.0)
    else:
        L.against_wall("Fridge", prefer="corner", access_depth=0.9, fits=lambda a: a.width <= 1.0)
    _dining_set(L)
    if counter is not None and _maybe(rng, 0.25):
        spec = choose_asset("Stool", rng)
        if spec is not None:
            f = counter.front
            dist = counter.local_size[2] / 2 + spec.depth / 2 + 0.1
            L.free_standing("Stool", spec, counter.center[0] + f[0] * dist, counter.center[2] + f[2] * dist,
                            counter.yaw + 180)
    for kind, p in (("GarbageCan", 0.7), ("HousePlant", 0.3), ("ShelvingUnit", 0.2)):
        if _maybe(rng, p):
            L.against_wall(kind, prefer="corner", access_depth=0.0 if kind != "ShelvingUnit" else 0.6,
                           fits=lambda a: a.depth <= 0.5)


def _along(receptacle: PlacedObject, item: PlacedObject) -> float:
    """Local x (along the width) of ``item`` on ``receptacle``."""
    dx = item.center[0] - receptacle.center[0]
    dz = item.center[2] - receptacle.center[2]
    y = np.radians(receptacle.yaw)
    return float(dx * np.cos(y) - dz * np.sin(y))


def _bedroom(L: RoomLayout) -> None:
    rng = L.rng
    bed = L.against_wall("Bed", prefer="center", avoid_door_walls=True, access_depth=0.7,
                         fits=lambda a: 0.6 <= a.height <= 1.3 and a.depth <= 2.3 and a.width <= 2.0)
    if bed is not None:
        first = _beside(L, bed, "SideTable", lamp_p=0.6)
        if first is not None and _maybe(rng, 0.5):
            _beside(L, bed, "SideTable", lamp_p=0.3)
    if _maybe(rng, 0.7):
        dresser = L.against_wall("Dresser", access_depth=0.7, fits=lambda a: a.depth <= 0.6)
        if dresser is not None and _maybe(rng, 0.25):
            L.on_top(dresser, "Television", near=0.0, fits=lambda a: a.height <= 0.9 and a.depth <= 0.45)
    if _maybe(rng, 0.5):
        desk = L.against_wall("Desk", access_depth=0.9, fits=lambda a: a.height <= 0.85 and a.depth <= 0.8 and a.width <= 1.6)
        if desk is not None:
            chair = choose_asset("Chair", rng, lambda a: a.height <= 1.05 and a.depth <= 0.6)
            if chair is not None:
                f = desk.front
                dist = desk.local_size[2] / 2 + chair.depth / 2 + 0.05
                L.free_standing("Chair", chair, desk.center[0] + f[0] * dist, desk.center[2] + f[2] * dist, desk.yaw + 180)
            if _maybe(rng, 0.5):
                L.on_top(desk, "Desktop", near=0.0)
            if _maybe(rng, 0.4):
                L.on_top(desk, "DeskLamp", fits=lambda a: a.height <= 0.6)
    for kind, p, access in (("ArmChair", 0.3, 0.6), ("GarbageCan", 0.5, 0.0),
                            ("HousePlant", 0.4, 0.0), ("Safe", 0.15, 0.5), ("ShelvingUnit", 0.2, 0.6)):
        if _maybe(rng, p):
            L.against_wall(kind, prefer="corner", access_depth=access, fits=lambda a: a.depth <= 0.9 and a.width <= 1.2)


def _bathroom(L: RoomLayout) -> None:
    rng = L.rng
    L.against_wall("Toilet", avoid_door_walls=True, access_depth=0.6)
    sink = L.against_wall("Sink", access_depth=0.6, fits=lambda a: a.height >= 0.8)
    if sink is not None:
        # the faucet stands on the basin's rim at 0.85 m, below the backsplash's top
        L.on_top(sink, "Faucet", near=0.0, back_gap=0.03, sink_into=sink.local_size[1] - 0.85, fits=lambda a: a.height <= 0.35 and a.depth <= 0.2)
        if _maybe(rng, 0.7):
            side_name = {0: "south", 180: "north", 90: "west", 270: "east"}[sink.yaw]
            along = sink.center[0] if sink.yaw in (0, 180) else sink.center[2]
            L.on_wall("HandTowelHolder", 1.05, near=along + sink.local_size[0] / 2 + 0.25, side_name=side_name)
    if _maybe(rng, 0.75):
        L.on_wall("TowelHolder", 1.25)
    if _maybe(rng, 0.4):
        washer = L.against_wall("WashingMachine", access_depth=0.7)
        if washer is not None and _maybe(rng, 0.6):
            _beside(L, washer, "ClothesDryer", lamp_p=0.0)
    for kind, p in (("GarbageCan", 0.6), ("HousePlant", 0.2)):
        if _maybe(rng, p):
            L.against_wall(kind, prefer="corner", access_depth=0.0)


RECIPES: dict[str, Callable[[RoomLayout], None]] = {
    "LivingRoom": _living_room,
    "Kitchen": _kitchen,
    "Bedroom": _bedroom,
    "Bathroom": _bathroom,
}


def furnish(plan: FloorPlan, rng: np.random.Generator) -> tuple[PlacedObject, ...]:
    """All objects of a house: doorways first, then each room's furniture, rooms in id order."""
    objects: list[PlacedObject] = [doorway_object(o, i) for i, o in enumerate(plan.openings)]
    for room in plan.rooms:
        layout = RoomLayout(room, plan, rng)
        RECIPES[room.room_type](layout)
        objects.extend(layout.objects)
    # objectIds come from positions; two objects never share one, but make sure of it
    seen: dict[str, int] = {}
    unique = []
    for o in objects:
        n = seen.get(o.object_id, 0)
        seen[o.object_id] = n + 1
        unique.append(o if n == 0 else _renamed(o, f"{o.object_id}|{n}"))
    return tuple(unique)


def _renamed(o: PlacedObject, object_id: str) -> PlacedObject:
    from dataclasses import replace

    return replace(o, object_id=object_id)

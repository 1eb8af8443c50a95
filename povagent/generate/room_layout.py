"""One room's furnishing state: its walls seen from inside, what is placed, what floor is taken
or kept free (in front of doorways and furniture), and where the next piece may go.

:mod:`povagent.generate.furnishing`'s room recipes place furniture through :class:`RoomLayout`;
every random choice comes from the layout's generator, in a fixed order, so a seed gives the
same house every time. What it must not do: choose which furniture a room holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from povagent.generate.assets import AssetSpec, asset_database, choose_asset
from povagent.generate.floorplan import FloorPlan, Opening, Rect, Room
from povagent.generate.scene import PlacedObject, object_id_for

#: Floor kept clear in front of each doorway, on both sides (m).
DOOR_CLEARANCE = 1.0


@dataclass(frozen=True)
class WallSide:
    """One wall of a room, seen from inside: where its surface is and which way it faces."""

    name: str
    axis: str  # "z": wall runs along x at z = line; "x": runs along z at x = line
    line: float
    start: float
    end: float
    yaw: int  # yaw of an object whose back is against this wall

    @property
    def length(self) -> float:
        """Usable length along the wall."""
        return self.end - self.start

    def footprint(self, t: float, width: float, depth: float, gap: float = 0.0) -> Rect:
        """Footprint of an object centred at ``t`` along the wall, ``gap`` off its surface."""
        if self.axis == "z":
            z0 = self.line + gap if self.yaw == 0 else self.line - gap - depth
            return Rect(t - width / 2, z0, t + width / 2, z0 + depth)
        x0 = self.line + gap if self.yaw == 90 else self.line - gap - depth
        return Rect(x0, t - width / 2, x0 + depth, t + width / 2)

    def along(self, rect: Rect) -> tuple[float, float]:
        """The interval a footprint covers along this wall."""
        return (rect.x0, rect.x1) if self.axis == "z" else (rect.z0, rect.z1)


OPPOSITE = {"south": "north", "north": "south", "west": "east", "east": "west"}


def wall_sides(room: Room) -> dict[str, WallSide]:
    """The four inner wall surfaces of a room."""
    r = room.interior
    return {
        "south": WallSide("south", "z", r.z0, r.x0, r.x1, 0),
        "north": WallSide("north", "z", r.z1, r.x0, r.x1, 180),
        "west": WallSide("west", "x", r.x0, r.z0, r.z1, 90),
        "east": WallSide("east", "x", r.x1, r.z0, r.z1, 270),
    }


def _front_rect(body: Rect, yaw: int, depth: float) -> Rect:
    """The strip of floor ``depth`` deep in front of a footprint facing ``yaw``."""
    if yaw == 0:
        return Rect(body.x0, body.z1, body.x1, body.z1 + depth)
    if yaw == 180:
        return Rect(body.x0, body.z0 - depth, body.x1, body.z0)
    if yaw == 90:
        return Rect(body.x1, body.z0, body.x1 + depth, body.z1)
    return Rect(body.x0 - depth, body.z0, body.x0, body.z1)


@dataclass
class RoomLayout:
    """The furnishing state of one room: what is placed, what floor is taken or kept free."""

    room: Room
    plan: FloorPlan
    rng: np.random.Generator
    objects: list[PlacedObject] = field(default_factory=list)
    bodies: list[tuple[Rect, float]] = field(default_factory=list)  # footprint, top
    access: list[Rect] = field(default_factory=list)
    keep_clear: list[Rect] = field(default_factory=list)
    top_use: dict[str, list[tuple[float, float]]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for o in self.plan.openings:
            if self.room.room_id not in o.rooms:
                continue
            self.keep_clear.append(_door_zone(o, self.room))

    # -- queries ----------------------------------------------------------------------------
    def sides(self) -> dict[str, WallSide]:
        """This room's walls."""
        return wall_sides(self.room)

    def side_has_door(self, side: WallSide) -> bool:
        """True when a doorway opens in this wall."""
        for o in self.plan.openings:
            if self.room.room_id in o.rooms and o.axis == side.axis and abs(o.line - side.line) < 0.06:
                return True
        return False

    def free(
        self, body: Rect, front: Rect | None = None, floor_from: float = 0.0, respect_access: bool = True
    ) -> bool:
        """True when a footprint (and its access strip) fits the room without collisions.

        ``floor_from`` > 0 checks a wall-mounted object: only furniture taller than that height
        collides with it. ``respect_access=False`` lets an object stand in the strip another
        keeps free in front of it (the coffee table in front of the sofa, a chair at a desk).
        """
        if not self.room.interior.contains(body.x0, body.z0, -1e-6) or not self.room.interior.contains(
            body.x1, body.z1, -1e-6
        ):
            return False
        for other, other_top in self.bodies:
            if floor_from < other_top and body.overlaps(other):
                return False
        if floor_from > 0.0:
            # wall-mounted: only tall things below it and doorways matter
            return not any(body.overlaps(z) for z in self.keep_clear)
        if any(body.overlaps(z) for z in self.keep_clear):
            return False
        if respect_access and any(body.overlaps(a) for a in self.access):
            return False
        if front is not None:
            if any(front.overlaps(b) for b, _ in self.bodies) or any(front.overlaps(z) for z in self.keep_clear):
                return False
        return True

    # -- placing ----------------------------------------------------------------------------
    def add(self, obj: PlacedObject, access_depth: float = 0.0) -> PlacedObject:
        """Record a placed object and the floor it takes (and keeps free in front of it)."""
        self.objects.append(obj)
        if obj.support in ("floor", "wall"):
            self.bodies.append((obj.rect, obj.top))
            if access_depth > 0:
                self.access.append(_front_rect(obj.rect, obj.yaw, access_depth))
        return obj

    def make(
        self,
        object_type: str,
        asset: AssetSpec,
        center: tuple[float, float, float],
        yaw: int,
        support: str = "floor",
        local_size: tuple[float, float, float] | None = None,
        flags: tuple[str, ...] = (),
    ) -> PlacedObject:
        """A PlacedObject with a rounded centre, a style drawn from the room's generator."""
        cx, cy, cz = (round(float(v), 4) for v in center)
        c = (cx, cy, cz)
        size = local_size or asset.size
        sx, sy, sz = (round(float(v), 4) for v in size)
        return PlacedObject(
            object_id=object_id_for(object_type, c),
            object_type=object_type,
            asset_id=asset.asset_id,
            center=c,
            local_size=(sx, sy, sz),
            yaw=yaw % 360,
            room_id=self.room.room_id,
            support=support,
            style=int(self.rng.integers(0, 1_000_000)),
            flags=flags,
        )

    def against_wall(
        self,
        object_type: str,
        *,
        fits: Callable[[AssetSpec], bool] | None = None,
        prefer: str = "any",
        sides: list[str] | None = None,
        avoid_door_walls: bool = False,
        access_depth: float = 0.5,
        asset: AssetSpec | None = None,
        near: float | None = None,
        largest: bool = False,
        local_size: tuple[float, float, float] | None = None,
    ) -> PlacedObject | None:
        """Place an object with its back to a wall; None when nothing fits.

        ``prefer`` is ``"center"`` (middle of the wall), ``"corner"`` (an end) or ``"any"``;
        ``near`` asks for the spot closest to that coordinate along the wall.
        """
        if asset is None:
            candidates = [a for a in asset_database()[object_type] if fits is None or fits(a)]
            if not candidates:
                return None
            if largest:
                candidates.sort(key=lambda a: (-a.width, a.asset_id))
            else:
                candidates = [candidates[int(self.rng.integers(len(candidates)))]]
        else:
            candidates = [asset]
        names = sides or ["south", "north", "west", "east"]
        all_sides = self.sides()
        order = [all_sides[n] for n in names]
        order = [order[i] for i in self.rng.permutation(len(order))]
        if avoid_door_walls:
            order.sort(key=lambda s: self.side_has_door(s))
        for spec in candidates:
            w, h, d = local_size or spec.size
            for side in order:
                ts = np.arange(side.start + w / 2, side.end - w / 2 + 1e-6, 0.05)
                valid = [
                    float(t)
                    for t in ts
                    if self.free(
                        side.footprint(float(t), w, d),
                        _front_rect(side.footprint(float(t), w, d), side.yaw, access_depth) if access_depth else None,
                    )
                ]
                if not valid:
                    continue
                t = self._pick(valid, side, prefer, near)
                body = side.footprint(t, w, d)
                cx, cz = body.center
                obj = self.make(object_type, spec, (cx, h / 2, cz), side.yaw, local_size=local_size)
                return self.add(obj, access_depth)
        return None

    def _pick(self, valid: list[float], side: WallSide, prefer: str, near: float | None) -> float:
        arr = np.asarray(valid)
        if near is not None:
            return float(arr[np.argmin(np.abs(arr - near))])
        if prefer == "center":
            mid = (side.start + side.end) / 2 + float(self.rng.uniform(-0.4, 0.4))
            return float(arr[np.argmin(np.abs(arr - mid))])
        if prefer == "corner":
            ends = np.minimum(np.abs(arr - side.start), np.abs(arr - side.end))
            best = np.flatnonzero(ends <= ends.min() + 1e-6)
            return float(arr[best[int(self.rng.integers(len(best)))]])
        return float(arr[int(self.rng.integers(len(arr)))])

    def free_standing(
        self, object_type: str, asset: AssetSpec, x: float, z: float, yaw: int, flags: tuple[str, ...] = ()
    ) -> PlacedObject | None:
        """Place an object at (x, z) facing ``yaw`` if the floor there is free."""
        w, h, d = asset.size
        sx, sz = (d, w) if yaw % 180 == 90 else (w, d)
        body = Rect(x - sx / 2, z - sz / 2, x + sx / 2, z + sz / 2)
        if not self.free(body, respect_access=False):
            return None
        return self.add(self.make(object_type, asset, (x, h / 2, z), yaw, flags=flags))

    def on_top(
        self,
        receptacle: PlacedObject,
        object_type: str,
        *,
        fits: Callable[[AssetSpec], bool] | None = None,
        asset: AssetSpec | None = None,
        near: float | None = None,
        back_gap: float = 0.03,
        sink_into: float = 0.0,
    ) -> PlacedObject | None:
        """Stand an object on a receptacle's top, back to the receptacle's back, facing its way."""
        spec = asset or choose_asset(
            object_type,
            self.rng,
            lambda a: (fits is None or fits(a)) and a.depth <= receptacle.local_size[2] - back_gap
            and a.width <= receptacle.local_size[0] - 0.04,
        )
        if spec is None:
            return None
        w, h, d = spec.size
        rw, _, rd = receptacle.local_size
        used = self.top_use.setdefault(receptacle.object_id, [])
        ts = np.arange(-rw / 2 + w / 2 + 0.02, rw / 2 - w / 2 - 0.02 + 1e-6, 0.05)
        valid = [float(t) for t in ts if all(t + w / 2 + 0.05 <= s or t - w / 2 - 0.05 >= e for s, e in used)]
        if not valid:
            return None
        arr = np.asarray(valid)
        t = float(arr[np.argmin(np.abs(arr - near))]) if near is not None else float(arr[int(self.rng.integers(len(arr)))])
        used.append((t - w / 2, t + w / 2))
        # local offset: along the receptacle's width, pushed to its back
        local = np.array([t, 0.0, -rd / 2 + back_gap + d / 2])
        yaw = np.radians(receptacle.yaw)
        rot = np.array([[np.cos(yaw), 0, np.sin(yaw)], [0, 1, 0], [-np.sin(yaw), 0, np.cos(yaw)]])
        world = rot @ local
        cx, cz = receptacle.center[0] + world[0], receptacle.center[2] + world[2]
        cy = receptacle.top - sink_into + h / 2
        obj = self.make(object_type, spec, (cx, cy, cz), receptacle.yaw, support=receptacle.object_id)
        return self.add(obj)

    def on_wall(self, object_type: str, height: float, near: float | None = None, side_name: str | None = None) -> PlacedObject | None:
        """Hang a wall object (towel holders) with its centre at ``height``."""
        spec = choose_asset(object_type, self.rng)
        if spec is None:
            return None
        w, h, d = spec.size
        names = [side_name] if side_name else ["south", "north", "west", "east"]
        sides = [self.sides()[n] for n in names]
        sides = [sides[i] for i in self.rng.permutation(len(sides))]
        for side in sides:
            ts = np.arange(side.start + w / 2 + 0.1, side.end - w / 2 - 0.1 + 1e-6, 0.05)
            # the towel hanging below reaches about 0.45 m down: keep that free of furniture
            valid = [float(t) for t in ts if self.free(side.footprint(float(t), w + 0.1, 0.3), floor_from=height - 0.5)]
            if not valid:
                continue
            t = self._pick(valid, side, "any", near)
            body = side.footprint(t, w, d)
            cx, cz = body.center
            obj = self.make(object_type, spec, (cx, height, cz), side.yaw, support="wall")
            self.objects.append(obj)
            self.bodies.append((side.footprint(t, w + 0.1, 0.3), height + h / 2))
            return obj
        return None


def _door_zone(o: Opening, room: Room) -> Rect:
    """Floor in front of a doorway, inside ``room``, that furniture must leave free."""
    cx, cz = room.rect.center
    if o.axis == "x":
        inward = 1.0 if cx > o.line else -1.0
        x0, x1 = sorted((o.line, o.line + inward * DOOR_CLEARANCE))
        return Rect(x0, o.start - 0.15, x1, o.end + 0.15)
    inward = 1.0 if cz > o.line else -1.0
    z0, z1 = sorted((o.line, o.line + inward * DOOR_CLEARANCE))
    return Rect(o.start - 0.15, z0, o.end + 0.15, z1)

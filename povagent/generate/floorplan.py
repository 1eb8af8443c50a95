"""Single-story floor plans: rectangular rooms, walls with doorways, an entrance.

What it is for: lay out a house the way ProcTHOR's houses look from inside (a kitchen, a living
room, bedrooms and bathrooms behind interior walls joined by doorways) and answer the geometric
questions the rest of the generator asks of it (which room is this point in, does a 0.4 m target
cube penetrate a wall, is it inside the house). What it must not do: furnish rooms, build meshes
or know about cameras.

A plan is made by splitting a rectangular footprint recursively (binary space partitioning)
into rooms of roughly the areas ProcTHOR gives each room type. Walls are modelled per room as
0.05 m slabs just inside the room's boundary, so the two faces of an interior wall can carry the
two rooms' paints and together are 0.1 m thick.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Ceiling height (ProcTHOR's houses use walls of about this height).
WALL_HEIGHT = 2.6
#: Thickness of one room's wall slab; an interior wall is two slabs.
WALL_SLAB = 0.05
#: Height of a doorway's opening (ProcTHOR's doorway assets are 2.07-2.13 m tall).
DOOR_HEIGHT = 2.1
#: The navigation and placement grid of AI2-THOR.
GRID = 0.25

ROOM_TYPES = ("Kitchen", "LivingRoom", "Bedroom", "Bathroom")

#: Target areas (m^2, low-high) per room type, about ProcTHOR's.
_ROOM_AREA = {
    "LivingRoom": (18.0, 28.0),
    "Kitchen": (12.0, 18.0),
    "Bedroom": (11.0, 17.0),
    "Bathroom": (5.0, 7.5),
}
_MIN_SIDE = {"LivingRoom": 3.25, "Kitchen": 2.75, "Bedroom": 3.0, "Bathroom": 2.0}


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangle in the xz plane (x0 <= x1, z0 <= z1)."""

    x0: float
    z0: float
    x1: float
    z1: float

    @property
    def width(self) -> float:
        """Extent along x."""
        return self.x1 - self.x0

    @property
    def depth(self) -> float:
        """Extent along z."""
        return self.z1 - self.z0

    @property
    def center(self) -> tuple[float, float]:
        """Centre (x, z)."""
        return ((self.x0 + self.x1) / 2.0, (self.z0 + self.z1) / 2.0)

    def contains(self, x: float, z: float, margin: float = 0.0) -> bool:
        """True when (x, z) lies inside, shrunk by ``margin`` on every side."""
        return self.x0 + margin <= x <= self.x1 - margin and self.z0 + margin <= z <= self.z1 - margin

    def overlaps(self, other: Rect, tolerance: float = 1e-6) -> bool:
        """True when the interiors overlap by more than ``tolerance``."""
        return (
            min(self.x1, other.x1) - max(self.x0, other.x0) > tolerance
            and min(self.z1, other.z1) - max(self.z0, other.z0) > tolerance
        )

    def inflate(self, margin: float) -> Rect:
        """The rectangle grown by ``margin`` on every side (shrunk when negative)."""
        return Rect(self.x0 - margin, self.z0 - margin, self.x1 + margin, self.z1 + margin)


@dataclass(frozen=True)
class Room:
    """A rectangular room of one ProcTHOR room type."""

    room_id: int
    room_type: str
    rect: Rect

    @property
    def interior(self) -> Rect:
        """The floor inside the wall slabs."""
        return self.rect.inflate(-WALL_SLAB)


@dataclass(frozen=True)
class Opening:
    """A doorway in a wall line: between two rooms, or the entrance from outside.

    ``axis`` names the coordinate that is constant along the wall line (``"x"``: the wall runs
    along z at ``x = line``); ``start``/``end`` bound the opening along the wall.
    """

    rooms: tuple[int, int | None]
    axis: str
    line: float
    start: float
    end: float
    asset_id: str = "Doorway_2"
    is_entrance: bool = False

    @property
    def width(self) -> float:
        """Clear width of the opening."""
        return self.end - self.start

    @property
    def center(self) -> tuple[float, float]:
        """Centre of the opening (x, z), on the wall line."""
        mid = (self.start + self.end) / 2.0
        return (self.line, mid) if self.axis == "x" else (mid, self.line)


@dataclass(frozen=True)
class WallSlab:
    """A box of wall: its xz footprint, vertical extent and the room whose paint it carries."""

    rect: Rect
    y0: float
    y1: float
    room_id: int


@dataclass(frozen=True)
class FloorPlan:
    """Rooms, openings and wall slabs of one house."""

    footprint: Rect
    rooms: tuple[Room, ...]
    openings: tuple[Opening, ...]
    slabs: tuple[WallSlab, ...] = field(default=())

    @property
    def entrance(self) -> Opening:
        """The opening to the outside."""
        return next(o for o in self.openings if o.is_entrance)

    def room_at(self, x: float, z: float) -> Room | None:
        """The room whose rectangle contains (x, z); None outside the house."""
        for room in self.rooms:
            if room.rect.contains(x, z):
                return room
        return None

    def inside_house(self, point: np.ndarray) -> bool:
        """True when a 3D point lies within the footprint, between floor and ceiling."""
        x, y, z = (float(v) for v in point)
        return self.room_at(x, z) is not None and 0.0 <= y <= WALL_HEIGHT

    def point_in_wall(self, point: np.ndarray) -> bool:
        """True when a 3D point lies inside a wall slab (lintels over doorways included)."""
        x, y, z = (float(v) for v in point)
        return any(s.rect.contains(x, z) and s.y0 <= y <= s.y1 for s in self.slabs)

    def cube_hits_wall(self, center: np.ndarray, half: float) -> bool:
        """True when an axis-aligned cube (centre, half size) penetrates a wall slab."""
        x, y, z = (float(v) for v in center)
        cube = Rect(x - half, z - half, x + half, z + half)
        for slab in self.slabs:
            if cube.overlaps(slab.rect, tolerance=1e-4) and y - half < slab.y1 and y + half > slab.y0:
                return True
        return False

    def cube_inside_house(self, center: np.ndarray, half: float) -> bool:
        """True when the cube's footprint lies inside the house and it fits under the ceiling."""
        x, y, z = (float(v) for v in center)
        corners = ((x - half, z - half), (x - half, z + half), (x + half, z - half), (x + half, z + half))
        return all(self.room_at(cx, cz) is not None for cx, cz in corners) and (
            y - half >= -1e-6 and y + half <= WALL_HEIGHT
        )

    def neighbours(self, room_id: int) -> list[int]:
        """Rooms joined to ``room_id`` by a doorway, in id order."""
        out = set()
        for o in self.openings:
            a, b = o.rooms
            if b is None:
                continue
            if a == room_id:
                out.add(b)
            elif b == room_id:
                out.add(a)
        return sorted(out)


# -- generation ---------------------------------------------------------------------------------
def _snap(v: float) -> float:
    return round(v / GRID) * GRID


def room_types_for(n_rooms: int, rng: np.random.Generator) -> list[str]:
    """ProcTHOR-like room mix: a living room and a kitchen, a bathroom, then bedrooms."""
    types = ["LivingRoom", "Kitchen"]
    if n_rooms >= 3:
        types.append("Bathroom")
    while len(types) < n_rooms:
        # a second bathroom in bigger houses, as ProcTHOR's larger layouts often have
        types.append("Bathroom" if len(types) >= 5 and rng.random() < 0.4 else "Bedroom")
    return types


def _split(
    rect: Rect, types: list[str], areas: list[float], rng: np.random.Generator
) -> list[tuple[Rect, str]] | None:
    """Split ``rect`` among ``types`` with areas proportional to ``areas``; None if it cannot."""
    if len(types) == 1:
        side = _MIN_SIDE[types[0]]
        if min(rect.width, rect.depth) < side - 1e-6:
            return None
        return [(rect, types[0])]
    order = rng.permutation(len(types))
    types = [types[i] for i in order]
    areas = [areas[i] for i in order]
    cut = int(rng.integers(1, len(types)))
    left_area = sum(areas[:cut])
    frac = left_area / sum(areas)
    along_x = rect.width >= rect.depth
    lo, hi = (rect.x0, rect.x1) if along_x else (rect.z0, rect.z1)
    line = _snap(lo + frac * (hi - lo))
    line = min(max(line, lo + 2.0), hi - 2.0)
    if along_x:
        a, b = Rect(rect.x0, rect.z0, line, rect.z1), Rect(line, rect.z0, rect.x1, rect.z1)
    else:
        a, b = Rect(rect.x0, rect.z0, rect.x1, line), Rect(rect.x0, line, rect.x1, rect.z1)
    left = _split(a, types[:cut], areas[:cut], rng)
    right = _split(b, types[cut:], areas[cut:], rng)
    if left is None or right is None:
        return None
    return left + right


def _shared_wall(a: Rect, b: Rect) -> tuple[str, float, float, float] | None:
    """The wall line two rooms share: (axis, line, start, end), or None."""
    eps = 1e-6
    if abs(a.x1 - b.x0) < eps or abs(b.x1 - a.x0) < eps:
        line = a.x1 if abs(a.x1 - b.x0) < eps else a.x0
        start, end = max(a.z0, b.z0), min(a.z1, b.z1)
        if end - start > eps:
            return ("x", line, start, end)
    if abs(a.z1 - b.z0) < eps or abs(b.z1 - a.z0) < eps:
        line = a.z1 if abs(a.z1 - b.z0) < eps else a.z0
        start, end = max(a.x0, b.x0), min(a.x1, b.x1)
        if end - start > eps:
            return ("z", line, start, end)
    return None


def _place_opening(
    rooms: tuple[int, int | None],
    axis: str,
    line: float,
    start: float,
    end: float,
    width: float,
    rng: np.random.Generator,
    asset_id: str,
    is_entrance: bool = False,
) -> Opening | None:
    # keep 0.35 m of wall either side so the jambs and corner furniture have room
    lo, hi = start + 0.35, end - 0.35 - width
    if hi < lo:
        return None
    s = round(float(lo + rng.random() * (hi - lo)), 2)
    return Opening(rooms, axis, line, s, round(s + width, 4), asset_id, is_entrance)


def _slabs_for_room(room: Room, openings: list[Opening]) -> list[WallSlab]:
    """The four walls of one room as slabs, cut around its openings (with lintels above)."""
    r = room.rect
    out: list[WallSlab] = []
    sides = (
        ("z", r.z0, r.x0, r.x1, +1),
        ("z", r.z1, r.x0, r.x1, -1),
        ("x", r.x0, r.z0, r.z1, +1),
        ("x", r.x1, r.z0, r.z1, -1),
    )
    for axis, line, start, end, inward in sides:
        cuts = sorted(
            (o.start, o.end)
            for o in openings
            if o.axis == axis and abs(o.line - line) < 1e-6 and o.start < end and o.end > start
            and room.room_id in o.rooms
        )
        pieces: list[tuple[float, float, float, float]] = []  # (start, end, y0, y1)
        cursor = start
        for s, e in cuts:
            if s > cursor:
                pieces.append((cursor, s, 0.0, WALL_HEIGHT))
            pieces.append((s, e, DOOR_HEIGHT, WALL_HEIGHT))
            cursor = max(cursor, e)
        if cursor < end:
            pieces.append((cursor, end, 0.0, WALL_HEIGHT))
        t0, t1 = sorted((line, line + inward * WALL_SLAB))
        for s, e, y0, y1 in pieces:
            rect = Rect(t0, s, t1, e) if axis == "x" else Rect(s, t0, e, t1)
            out.append(WallSlab(rect, y0, y1, room.room_id))
    return out


def generate_floorplan(rng: np.random.Generator, n_rooms: int | None = None) -> FloorPlan:
    """A random single-story plan of ``n_rooms`` rooms (3 to 6 when not given)."""
    if n_rooms is None:
        n_rooms = int(rng.choice([3, 4, 5, 6], p=[0.2, 0.35, 0.3, 0.15]))
    types = room_types_for(n_rooms, rng)
    for _attempt in range(200):
        areas = [float(rng.uniform(*_ROOM_AREA[t])) for t in types]
        total = sum(areas)
        aspect = float(rng.uniform(1.0, 1.6))
        width = _snap(np.sqrt(total * aspect))
        depth = _snap(total / width)
        footprint = Rect(0.0, 0.0, width, depth)
        split = _split(footprint, list(types), areas, rng)
        if split is None:
            continue
        plan = _connect(footprint, split, rng)
        if plan is not None:
            return plan
    raise RuntimeError("could not lay out a floor plan; this is a bug in the room sizes")


def _connect(footprint: Rect, split: list[tuple[Rect, str]], rng: np.random.Generator) -> FloorPlan | None:
    """Join the rooms by doorways (a tree from the living room) and add the entrance."""
    # centre the house on the origin, as ProcTHOR's scenes roughly are
    ox, oz = _snap(footprint.width / 2.0), _snap(footprint.depth / 2.0)

    def shift(r: Rect) -> Rect:
        return Rect(r.x0 - ox, r.z0 - oz, r.x1 - ox, r.z1 - oz)

    rooms = tuple(Room(i, t, shift(r)) for i, (r, t) in enumerate(split))
    footprint = shift(footprint)
    width = 1.0
    openings: list[Opening] = []
    hub = next(r.room_id for r in rooms if r.room_type == "LivingRoom")
    seen = {hub}
    queue = [hub]
    while queue:
        current = queue.pop(0)
        for other in rooms:
            if other.room_id in seen:
                continue
            # bathrooms hang off one room only: a bathroom is never a corridor
            if rooms[current].room_type == "Bathroom":
                continue
            wall = _shared_wall(rooms[current].rect, other.rect)
            if wall is None:
                continue
            axis, line, start, end = wall
            o = _place_opening((current, other.room_id), axis, line, start, end, width, rng, "Doorway_2")
            if o is None:
                continue
            openings.append(o)
            seen.add(other.room_id)
            queue.append(other.room_id)
    if len(seen) != len(rooms):
        return None
    hub_rect = rooms[hub].rect
    exterior = []
    if abs(hub_rect.z0 - footprint.z0) < 1e-6:
        exterior.append(("z", hub_rect.z0, hub_rect.x0, hub_rect.x1))
    if abs(hub_rect.z1 - footprint.z1) < 1e-6:
        exterior.append(("z", hub_rect.z1, hub_rect.x0, hub_rect.x1))
    if abs(hub_rect.x0 - footprint.x0) < 1e-6:
        exterior.append(("x", hub_rect.x0, hub_rect.z0, hub_rect.z1))
    if abs(hub_rect.x1 - footprint.x1) < 1e-6:
        exterior.append(("x", hub_rect.x1, hub_rect.z0, hub_rect.z1))
    if not exterior:
        return None
    axis, line, start, end = exterior[int(rng.integers(len(exterior)))]
    entrance = _place_opening((hub, None), axis, line, start, end, width, rng, "Doorway_5", True)
    if entrance is None:
        return None
    openings.append(entrance)
    slabs: list[WallSlab] = []
    for room in rooms:
        slabs.extend(_slabs_for_room(room, openings))
    return FloorPlan(footprint, rooms, tuple(openings), tuple(slabs))

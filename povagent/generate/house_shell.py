"""The house's shell: each room's floor and ceiling, and the wall slabs with their baseboards,
in a paint and a floor drawn per room (tiles in kitchens and bathrooms, wood elsewhere).

What it must not do: build furniture (:mod:`povagent.generate.meshes`), cast rays or shade pixels.
"""

from __future__ import annotations

import numpy as np

from povagent.generate.floorplan import WALL_HEIGHT, FloorPlan
from povagent.generate.mesh_parts import CEILING, FLOOR_TILE, FLOOR_WOOD, PLAIN, WALL, MeshParts, box_mesh, pick, rgb

WALL_PAINTS = [rgb(c) for c in ("#e9e4d8", "#d6dde3", "#e8dcc8", "#cfd8c7", "#e3d3d3", "#f0ede5", "#c9d3dc", "#ddd5c2")]
FLOOR_WOODS = [rgb(c) for c in ("#a57a52", "#8d6241", "#c19a6b", "#7b5a3c", "#b08968")]
FLOOR_TILES = [rgb(c) for c in ("#d8d4cc", "#bfc5c9", "#e6e0d4", "#9ea7ad", "#cfc6b8")]


def add_structure(mesh: MeshParts, plan: FloorPlan, rng: np.random.Generator) -> dict[int, tuple]:
    """Floors, ceilings and wall slabs of every room; returns each room's wall paint."""
    paints: dict[int, tuple] = {}
    for room in plan.rooms:
        paints[room.room_id] = pick(rng, WALL_PAINTS)
        r = room.rect
        tiled = room.room_type in ("Kitchen", "Bathroom")
        floor = pick(rng, FLOOR_TILES if tiled else FLOOR_WOODS)
        quad = np.array([[r.x0, 0, r.z0], [r.x1, 0, r.z0], [r.x1, 0, r.z1], [r.x0, 0, r.z1]], dtype=float)
        tris = np.array([[0, 1, 2], [0, 2, 3]])
        mesh.add(quad, tris, floor, FLOOR_TILE if tiled else FLOOR_WOOD, 0, room.room_id, closed=False)
        mesh.add(quad + [0, WALL_HEIGHT, 0], tris, (0.96, 0.96, 0.95), CEILING, 0, room.room_id, closed=False)
    for slab in plan.slabs:
        r = slab.rect
        mesh.add(*box_mesh((r.x0, slab.y0, r.z0), (r.x1, slab.y1, r.z1)), paints[slab.room_id], WALL, 0, slab.room_id)
        if slab.y0 == 0.0:
            # a baseboard along the foot of the wall, 1 cm proud of it
            t = 0.01
            lo = (r.x0 - t, 0.0, r.z0 - t)
            hi = (r.x1 + t, 0.08, r.z1 + t)
            mesh.add(*box_mesh(lo, hi), (0.93, 0.92, 0.9), PLAIN, 0, slab.room_id)
    return paints

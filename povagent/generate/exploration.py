"""Robot exploration: reachable grid, a tour from the entrance through every room, frame poses.

What it is for: reproduce the paper's capture protocol. The agent's reachable positions are
AI2-THOR's 0.25 m grid cells that a robot of radius 0.2 m can stand on and reach from the
entrance; the tour visits the rooms in depth-first order from the entrance room, and the frame
budget (up to 30) is shared among rooms by their number of reachable cells, spread within each
room by farthest-point sampling, so the spacing adapts to how much floor the house has. Each
frame looks the way that shows the most furniture (scored on a coarse instance mask), from
0.9 m with a 30 degree downward tilt and a 100 degree field of view. What it must not do:
render full frames or decide which objects count as visible (the writer reads the full masks).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from povagent.generate.floorplan import GRID, Rect
from povagent.generate.furnishing import DOOR_FRAME_TRIM
from povagent.generate.meshes import JAMB_OVERLAP
from povagent.generate.renderer import Renderer
from povagent.generate.scene import House
from povagent.geometry.camera import Camera

AGENT_RADIUS = 0.2
CAMERA_HEIGHT = 0.9
CAMERA_HORIZON = 30.0
FOV = 100.0
#: Headings tried per frame position, and the side of the coarse mask that scores them.
HEADINGS = 12
PROBE_SIZE = 48


@dataclass(frozen=True)
class ReachableGrid:
    """Reachable cell centres (x, z) and the room each one is in."""

    points: np.ndarray
    rooms: np.ndarray
    start: int


def blockers(house: House) -> list[Rect]:
    """Footprints the robot body cannot overlap: wall slabs, door jambs, floor furniture."""
    out = [s.rect for s in house.plan.slabs if s.y0 == 0.0]
    for o in house.objects:
        if o.object_type == "Doorway":
            r = o.rect
            t = DOOR_FRAME_TRIM + JAMB_OVERLAP
            if r.width > r.depth:  # jambs at both ends of the opening
                out += [Rect(r.x0, r.z0, r.x0 + t, r.z1), Rect(r.x1 - t, r.z0, r.x1, r.z1)]
            else:
                out += [Rect(r.x0, r.z0, r.x1, r.z0 + t), Rect(r.x0, r.z1 - t, r.x1, r.z1)]
        elif o.support == "floor":
            out.append(o.rect)
    return out


def _room_id(house: House, x: float, z: float) -> int:
    room = house.plan.room_at(x, z)
    if room is None:  # the grid is cut to the rooms, so every reachable cell lies in one
        raise ValueError(f"reachable point ({x}, {z}) lies in no room")
    return room.room_id


def reachable_grid(house: House) -> ReachableGrid:
    """Grid cells a robot can stand on and reach from just inside the entrance."""
    fp = house.plan.footprint
    xs = np.arange(np.ceil(fp.x0 / GRID) * GRID, fp.x1 + 1e-9, GRID)
    zs = np.arange(np.ceil(fp.z0 / GRID) * GRID, fp.z1 + 1e-9, GRID)
    gx, gz = np.meshgrid(xs, zs, indexing="ij")
    ok = np.ones(gx.shape, dtype=bool)
    ok &= (gx > fp.x0 + AGENT_RADIUS) & (gx < fp.x1 - AGENT_RADIUS)
    ok &= (gz > fp.z0 + AGENT_RADIUS) & (gz < fp.z1 - AGENT_RADIUS)
    for r in blockers(house):
        q = r.inflate(AGENT_RADIUS - 1e-6)
        ok &= ~((gx > q.x0) & (gx < q.x1) & (gz > q.z0) & (gz < q.z1))

    entrance = house.plan.entrance
    ex, ez = entrance.center
    cx, cz = house.plan.rooms[entrance.rooms[0]].rect.center
    inward = np.array([cx - ex, cz - ez]) * (np.array([1.0, 0.0]) if entrance.axis == "x" else np.array([0.0, 1.0]))
    inward = inward / (np.linalg.norm(inward) or 1.0)
    target = np.array([ex, ez]) + 0.6 * inward
    cand = np.argwhere(ok)
    if len(cand) == 0:
        raise RuntimeError("no reachable floor in this house")
    d2 = (gx[ok] - target[0]) ** 2 + (gz[ok] - target[1]) ** 2
    si, sj = cand[int(np.argmin(d2))]

    seen = np.zeros_like(ok)
    seen[si, sj] = True
    queue = deque([(si, sj)])
    while queue:
        i, j = queue.popleft()
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            a, b = i + di, j + dj
            if 0 <= a < ok.shape[0] and 0 <= b < ok.shape[1] and ok[a, b] and not seen[a, b]:
                seen[a, b] = True
                queue.append((a, b))
    idx = np.argwhere(seen)
    points = np.stack([gx[seen], gz[seen]], axis=1).round(4)
    rooms = np.array([_room_id(house, float(x), float(z)) for x, z in points])
    start = int(np.flatnonzero((idx[:, 0] == si) & (idx[:, 1] == sj))[0])
    return ReachableGrid(points, rooms, start)


def room_order(house: House, first: int) -> list[int]:
    """Rooms in depth-first order through the doorways, from ``first``."""
    order: list[int] = []
    stack = [first]
    while stack:
        r = stack.pop()
        if r in order:
            continue
        order.append(r)
        stack.extend(reversed([n for n in house.plan.neighbours(r) if n not in order]))
    return order


def allocate(counts: list[int], budget: int) -> list[int]:
    """Share ``budget`` frames among rooms by reachable cells: at least one each, largest remainder."""
    n = len(counts)
    if budget <= 0 or n == 0:
        return [0] * n
    base = [1 if c > 0 and budget >= n else 0 for c in counts]
    rest = budget - sum(base)
    total = sum(counts)
    share = [rest * c / total for c in counts] if total else [0.0] * n
    out = [b + int(np.floor(s)) for b, s in zip(base, share)]
    order = sorted(range(n), key=lambda i: (-(share[i] - np.floor(share[i])), i))
    for i in order[: budget - sum(out)]:
        out[i] += 1
    return [min(o, c) for o, c in zip(out, counts)]


def farthest_points(points: np.ndarray, k: int, seed_point: np.ndarray) -> list[int]:
    """Indices of ``k`` points spread by farthest-point sampling, away from ``seed_point`` first."""
    chosen: list[int] = []
    dist = np.linalg.norm(points - seed_point, axis=1)
    for _ in range(min(k, len(points))):
        i = int(np.argmax(dist))
        chosen.append(i)
        dist = np.minimum(dist, np.linalg.norm(points - points[i], axis=1))
    return chosen


def best_heading(renderer: Renderer, x: float, z: float) -> float:
    """The yaw (degrees) whose view shows the most objects, scored on a coarse instance mask."""
    best, best_score = 0.0, -1.0
    for k in range(HEADINGS):
        yaw = 360.0 * k / HEADINGS
        cam = Camera((x, CAMERA_HEIGHT, z), yaw, CAMERA_HORIZON, FOV, PROBE_SIZE, PROBE_SIZE)
        mask = renderer.instance_mask(cam)
        counts = np.bincount(mask.ravel().astype(np.int64))[1:]
        objects = int(np.sum(counts >= 4))
        score = objects + 2.0 * float(np.sum(counts)) / mask.size
        if score > best_score + 1e-9:
            best, best_score = yaw, score
    return best


def plan_tour(house: House, renderer: Renderer, frames: int = 30) -> list[Camera]:
    """Exploration cameras: a tour from the entrance through every room, ``frames`` at most."""
    grid = reachable_grid(house)
    entrance_room = house.plan.entrance.rooms[0]
    order = [r for r in room_order(house, entrance_room)]
    counts = [int(np.sum(grid.rooms == r)) for r in order]
    budget = min(frames, len(grid.points))
    shares = allocate(counts, budget)
    cameras: list[Camera] = []
    here = grid.points[grid.start]
    for room_id, k in zip(order, shares):
        if k == 0:
            continue
        cells = grid.points[grid.rooms == room_id]
        centre = np.array(house.plan.rooms[room_id].rect.center)
        picks = cells[farthest_points(cells, k, centre)]
        # visit the picked spots nearest-first from where the robot enters the room
        remaining = list(range(len(picks)))
        while remaining:
            j = min(remaining, key=lambda i: (float(np.linalg.norm(picks[i] - here)), i))
            remaining.remove(j)
            x, z = (float(v) for v in picks[j])
            yaw = best_heading(renderer, x, z)
            cameras.append(Camera((x, CAMERA_HEIGHT, z), yaw, CAMERA_HORIZON, FOV, 512, 512))
            here = picks[j]
    return cameras

"""The floor the robot's body may cross: walls, door jambs and floor furniture block it.

What it is for: ``move`` must stop where the robot would bump into something, with the same
obstacles the generator planned the exploration with (its reachable grid and blockers), and a
0.25 m body. A move is walked in short steps; each step must keep the body clear of every
blocker it was not already touching (a frame taken close to a sofa must not trap the robot)
and stay on the reachable floor (near a reachable grid cell, so it never slips through a wall
or out of the house). What it must not do: render, or know about tools and budgets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from povagent.generate.exploration import blockers, reachable_grid
from povagent.generate.floorplan import GRID
from povagent.generate.scene import House

#: The robot body's radius (m) for moves.
BODY_RADIUS = 0.25
#: The length of one step of a move (m): shorter than any blocker is thin.
STEP = 0.02
#: The farthest a point may lie from a reachable cell centre and still be on the reachable floor.
ON_GRID = GRID * math.sqrt(0.5) + 1e-6
#: The longest move taken in one call (m): longer requests are cut to it, and said so.
MAX_MOVE = 10.0


@dataclass(frozen=True)
class MoveResult:
    """Where a move ended, how far it got (m) and whether something stopped it."""

    x: float
    z: float
    travelled: float
    blocked: bool


class Floor:
    """The blockers (as arrays) and the reachable cells of one house."""

    def __init__(self, house: House) -> None:
        rects = [r.inflate(BODY_RADIUS) for r in blockers(house)]
        self._boxes = np.array([[r.x0, r.z0, r.x1, r.z1] for r in rects], dtype=float).reshape(-1, 4)
        self._cells = reachable_grid(house).points.astype(float)

    @property
    def cells(self) -> np.ndarray:
        """The reachable cell centres (n, 2): the floor the robot may stand on."""
        return self._cells

    def _touching(self, x: float, z: float) -> np.ndarray:
        b = self._boxes
        return (b[:, 0] < x) & (x < b[:, 2]) & (b[:, 1] < z) & (z < b[:, 3])

    def _on_floor(self, x: float, z: float) -> bool:
        d2 = (self._cells[:, 0] - x) ** 2 + (self._cells[:, 1] - z) ** 2
        return bool(d2.min() <= ON_GRID * ON_GRID) if len(d2) else False

    def move(self, x: float, z: float, dx: float, dz: float) -> MoveResult:
        """Walk from (x, z) by (dx, dz); stop before the first step that would collide."""
        length = math.hypot(dx, dz)
        if length > MAX_MOVE:
            dx, dz, length = dx * MAX_MOVE / length, dz * MAX_MOVE / length, MAX_MOVE
        already = self._touching(x, z)  # blockers the start overlaps do not hold the body
        steps = max(1, math.ceil(length / STEP))
        last = (x, z)
        for k in range(1, steps + 1):
            px, pz = x + dx * k / steps, z + dz * k / steps
            if (self._touching(px, pz) & ~already).any() or not self._on_floor(px, pz):
                return MoveResult(last[0], last[1], math.hypot(last[0] - x, last[1] - z), True)
            last = (px, pz)
        return MoveResult(last[0], last[1], length, False)

    def clear(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """Whether each straight walk from ``starts[k]`` to ``ends[k]`` ((n, 2) floor points)
        keeps the body clear of every blocker its start does not already touch, as :meth:`move`
        rules; exact (the segment against each box), so a walk it passes ``move`` walks. The
        reachable floor is not checked: callers walk between neighbouring reachable cells."""
        p = np.asarray(starts, dtype=float).reshape(-1, 1, 2)
        d = np.asarray(ends, dtype=float).reshape(-1, 1, 2) - p
        lo, hi = self._boxes[None, :, :2], self._boxes[None, :, 2:]
        with np.errstate(divide="ignore", invalid="ignore"):
            t0, t1 = (lo - p) / d, (hi - p) / d
        inside_axis = (lo < p) & (p < hi)  # a still axis crosses the box only from within its span
        enter = np.where(d == 0, np.where(inside_axis, -np.inf, np.inf), np.minimum(t0, t1)).max(axis=2)
        leave = np.where(d == 0, np.where(inside_axis, np.inf, -np.inf), np.maximum(t0, t1)).min(axis=2)
        crosses = (enter < leave) & (enter < 1.0) & (leave > 0.0)
        already = inside_axis.all(axis=2)
        return ~(crosses & ~already).any(axis=1)

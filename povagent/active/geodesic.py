"""The geodesic shortest path on a floor grid: the ``l_i`` of SPL for the navigate task.

What it is for: success weighted by path length (SPL, Anderson et al. 2018) divides by the
shortest path an agent could have walked, which on a house's floor is the geodesic, not the
straight line. The floor is the set of grid cells a robot may stand on (the generator's
reachable cells); the path is Dijkstra's over them, 8-connected (a diagonal step only between
two free orthogonal neighbours, so it never cuts a corner), each step optionally checked by the
caller's rule for a straight walk (``clear``: the same body and obstacles as ``move``). The
path starts from the free cell nearest the start pose (the straight step to it is counted) and
ends at the first goal cell reached. What it must not do: know about houses, rendering or
tools (:mod:`.navigation` decides which cells are goals).
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: A walk check for many straight steps at once: ``clear(starts, ends)`` with (n, 2) arrays of
#: floor points (x, z) gives a boolean per step.
ClearFn = Callable[[np.ndarray, np.ndarray], np.ndarray]

_STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))


@dataclass(frozen=True)
class GeodesicPath:
    """A shortest path: its length (m) and the floor points (x, z) it visits, start first."""

    length: float
    points: tuple[tuple[float, float], ...]


class FloorGrid:
    """Free cells of a square grid on the floor: cell (i, j) has its centre at
    ``origin + (i, j) * size``; ``free[i, j]`` says the robot may stand there."""

    def __init__(self, free: np.ndarray, origin: tuple[float, float], size: float, clear: ClearFn | None = None) -> None:
        self.free = np.asarray(free, dtype=bool)
        self.origin = (float(origin[0]), float(origin[1]))
        self.size = float(size)
        self._clear = clear
        self._edges: dict[tuple[int, int], list[tuple[tuple[int, int], float]]] | None = None

    @classmethod
    def of_cells(cls, points: np.ndarray, size: float, clear: ClearFn | None = None) -> FloorGrid:
        """The grid whose free cells are the cell centres ``points`` ((n, 2) floor points on a
        ``size`` lattice, such as the generator's reachable cells)."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(points) == 0:
            return cls(np.zeros((0, 0), dtype=bool), (0.0, 0.0), size, clear)
        origin = points.min(axis=0)
        index = np.rint((points - origin) / size).astype(int)
        free = np.zeros(tuple(index.max(axis=0) + 1), dtype=bool)
        free[index[:, 0], index[:, 1]] = True
        return cls(free, (float(origin[0]), float(origin[1])), size, clear)

    def centre(self, cell: tuple[int, int]) -> tuple[float, float]:
        """The floor point (x, z) of a cell's centre."""
        return self.origin[0] + cell[0] * self.size, self.origin[1] + cell[1] * self.size

    def cells(self) -> list[tuple[int, int]]:
        """Every free cell."""
        return [(int(i), int(j)) for i, j in np.argwhere(self.free)]

    def _is_free(self, i: int, j: int) -> bool:
        return 0 <= i < self.free.shape[0] and 0 <= j < self.free.shape[1] and bool(self.free[i, j])

    def edges(self) -> dict[tuple[int, int], list[tuple[tuple[int, int], float]]]:
        """Each free cell's neighbours and the step's length, built once (the walk check runs
        over every step in one call)."""
        if self._edges is not None:
            return self._edges
        steps: list[tuple[tuple[int, int], tuple[int, int], float]] = []
        for i, j in self.cells():
            for di, dj in _STEPS:
                if not self._is_free(i + di, j + dj):
                    continue
                if di and dj and not (self._is_free(i + di, j) and self._is_free(i, j + dj)):
                    continue  # a diagonal step never cuts a corner
                steps.append(((i, j), (i + di, j + dj), self.size * math.hypot(di, dj)))
        ok = np.ones(len(steps), dtype=bool)
        if self._clear is not None and steps:
            starts = np.array([self.centre(a) for a, _, _ in steps])
            ends = np.array([self.centre(b) for _, b, _ in steps])
            ok = np.asarray(self._clear(starts, ends), dtype=bool)
        edges: dict[tuple[int, int], list[tuple[tuple[int, int], float]]] = {c: [] for c in self.cells()}
        for (a, b, length), passes in zip(steps, ok):
            if passes:
                edges[a].append((b, length))
        self._edges = edges
        return edges

    def nearest(self, x: float, z: float) -> tuple[int, int] | None:
        """The free cell whose centre is nearest (x, z), or ``None`` when none is free."""
        cells = np.argwhere(self.free)
        if len(cells) == 0:
            return None
        centres = np.asarray(self.origin) + cells * self.size
        k = int(np.argmin(((centres - (x, z)) ** 2).sum(axis=1)))
        return int(cells[k][0]), int(cells[k][1])

    def shortest(self, start: tuple[float, float], goal: Callable[[tuple[int, int]], bool]) -> GeodesicPath | None:
        """The shortest path from the floor point ``start`` to the nearest cell for which
        ``goal(cell)`` holds (Dijkstra), or ``None`` when no goal cell is reachable."""
        first = self.nearest(*start)
        if first is None:
            return None
        edges = self.edges()
        head = math.hypot(self.centre(first)[0] - start[0], self.centre(first)[1] - start[1])
        best = {first: head}
        came: dict[tuple[int, int], tuple[int, int]] = {}
        queue = [(head, first)]
        while queue:
            cost, cell = heapq.heappop(queue)
            if cost > best[cell]:
                continue
            if goal(cell):
                route = [cell]
                while route[-1] in came:
                    route.append(came[route[-1]])
                points = (start, *(self.centre(c) for c in reversed(route)))
                return GeodesicPath(cost, tuple((float(x), float(z)) for x, z in points))
            for nxt, length in edges[cell]:
                if cost + length < best.get(nxt, math.inf):
                    best[nxt] = cost + length
                    came[nxt] = cell
                    heapq.heappush(queue, (cost + length, nxt))
        return None


def path_length(points: list[tuple[float, float]] | tuple[tuple[float, float], ...]) -> float:
    """The length (m) of a walk through floor points (x, z), in order."""
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(points))


def spl(success: bool, shortest: float, walked: float) -> float:
    """Success weighted by path length for one episode: ``S * l / max(p, l)`` (Anderson et al.
    2018); a failure is 0, and a zero-length shortest path walked in zero metres is 1."""
    if not success:
        return 0.0
    longest = max(walked, shortest)
    return 1.0 if longest == 0 else shortest / longest

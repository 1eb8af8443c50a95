"""Lookup tables keyed by (group, cell): what lies near a point, found in one sorted search.

What it is for: :mod:`povagent.generate.visible_face` asks, for hundreds of thousands of hit
points a frame, which faces of a group (or which watched edges) come near each point. Space is
cut into cubic cells; an item is listed under every (group, cell) key its grown box reaches; a
point's key is found with one ``searchsorted``. What it must not do: decide anything (it only
lists candidates; the exact tests are the caller's).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Cell coordinates are packed into one integer key, this many values an axis (a house spans
#: far less than 2048 cells of the sizes used).
_CELL_SPAN = 2048


@dataclass(frozen=True)
class CellTable:
    """Sorted (group, cell) keys and, from ``starts[k]`` to ``starts[k + 1]`` in ``items``,
    what is listed under key k."""

    keys: np.ndarray
    starts: np.ndarray
    items: np.ndarray

    @classmethod
    def build(cls, key_lists: list[np.ndarray], item_lists: list[np.ndarray], order_by: np.ndarray | None = None) -> CellTable:
        """From key arrays and the item of each key; within a key, items in ``order_by``'s
        order (ascending), else by item."""
        key = np.concatenate(key_lists).astype(np.int64)
        item = np.concatenate(item_lists).astype(np.int64)
        rank = item if order_by is None else order_by[item]
        order = np.lexsort((rank, key))
        key, item = key[order], item[order]
        keys, starts = np.unique(key, return_index=True)
        return cls(keys, np.append(starts, len(key)), item)

    def find(self, key: np.ndarray) -> np.ndarray:
        """The index of each key in the table, -1 where it is not listed."""
        if not len(self.keys):
            return np.full(len(key), -1, dtype=np.int64)
        at = np.minimum(np.searchsorted(self.keys, key), len(self.keys) - 1)
        return np.where(self.keys[at] == key, at, -1)

    def explode(self, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For listed entries ``at`` (>= 0): (position in ``at``, item) for every listed item."""
        counts = self.starts[at + 1] - self.starts[at]
        row = np.repeat(np.arange(len(at)), counts)
        slot = np.arange(len(row)) - np.repeat(np.cumsum(counts) - counts, counts)
        return row, self.items[self.starts[at][row] + slot]


def cell(x: np.ndarray, size: float) -> np.ndarray:
    """The cell coordinates of positions, in cells of ``size`` metres."""
    return np.floor(np.asarray(x, dtype=np.float64) * (1.0 / size)).astype(np.int64)


def pack(group: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """One integer key per (group, cell x, y, z)."""
    half = _CELL_SPAN // 2
    key = np.asarray(group, dtype=np.int64)
    for k in range(3):
        key = key * _CELL_SPAN + (np.clip(cells[..., k], -half, half - 1) + half)
    return key


def key_of(group: np.ndarray, point: list[np.ndarray], size: float) -> np.ndarray:
    """The (group, cell) key of each point: :func:`pack` of its cells, one coordinate at a time."""
    half = _CELL_SPAN // 2
    key = np.asarray(group, dtype=np.int64)
    for p in point:
        c = cell(p, size)
        np.clip(c, -half, half - 1, out=c)
        c += half
        key = key * _CELL_SPAN
        key += c
    return key


def boxes_keys(group: np.ndarray, low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The keys of every cell from ``low[i]`` to ``high[i]`` (inclusive) of each item i, in its
    group, and the item of each key."""
    dims = high - low + 1  # (n, 3)
    sizes = dims.prod(axis=1)
    item = np.repeat(np.arange(len(group)), sizes)
    local = np.arange(len(item)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    dy, dz = dims[item, 1], dims[item, 2]
    cells = np.stack([local // (dy * dz), (local // dz) % dy, local % dz], axis=1) + low[item]
    return pack(group[item], cells), item


def unique_pairs(ray: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct (ray, group) pairs with a group (>= 0), sorted by ray then group."""
    keep = group >= 0
    packed = ray[keep].astype(np.int64) * (1 << 32) + group[keep]
    packed.sort()
    fresh = np.ones(len(packed), dtype=bool)
    fresh[1:] = packed[1:] != packed[:-1]
    packed = packed[fresh]
    return packed >> 32, packed & ((1 << 32) - 1)


@dataclass(frozen=True)
class CellMask:
    """A dense grid of cells (any group) marked where a table lists something: a point in an
    unmarked cell has no key in the table (whatever its group), so it needs no lookup. Its
    cells are computed as :func:`key_of` computes a key's (:func:`cell` of the same float64
    coordinates, clipped alike), so the mask answers exactly as the table would."""

    origin: np.ndarray  # (3,) float64: the first cell's coordinates (whole numbers)
    shape: tuple[int, int, int]
    marked: np.ndarray  # flat bool, x slowest, with an unmarked layer of cells all round
    size: float

    #: a grid larger than this many cells is not built (every point is then looked up)
    MAX_CELLS = 1 << 26

    @classmethod
    def build(cls, low: np.ndarray, high: np.ndarray, size: float) -> CellMask | None:
        """From the (n, 3) inclusive cell ranges a table's keys were made from (:func:`boxes_keys`);
        ``None`` when there are none, the grid would be too large, or it reaches the cells where
        :func:`pack` clips (a key there may stand for a point beyond: a house spans far less)."""
        half = _CELL_SPAN // 2
        if not len(low) or low.min() <= -half or high.max() >= half - 1:
            return None
        # one unmarked cell all round: a point beyond the grid is clipped onto it
        origin = low.min(axis=0) - 1
        dims = high.max(axis=0) - origin + 2
        if int(np.prod(dims.astype(np.float64))) > cls.MAX_CELLS:
            return None
        # inclusion-exclusion at the 8 corners of each box, then prefix sums along the axes
        count = np.zeros(tuple(int(k) + 1 for k in dims), dtype=np.int32)
        lo, hi = low - origin, high - origin + 1
        for corner in range(8):
            pick = [(hi if corner >> k & 1 else lo)[:, k] for k in range(3)]
            sign = -1 if bin(corner).count("1") % 2 else 1
            np.add.at(count, tuple(pick), sign)
        for axis in range(3):
            np.cumsum(count, axis=axis, out=count)
        marked = count[: dims[0], : dims[1], : dims[2]] > 0
        return cls(origin.astype(np.float64), (int(dims[0]), int(dims[1]), int(dims[2])), marked.ravel(), size)

    def covers(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Whether each point (finite float64 coordinates, as the table's keys are computed) lies
        in a marked cell."""
        # the cell as ``cell`` computes it, then its place in the grid, all in float64 (whole
        # numbers far below 2**53: exact), clipped onto the unmarked border beyond the grid
        index: np.ndarray | None = None
        for k, coord in enumerate((x, y, z)):
            c = np.multiply(coord, 1.0 / self.size, dtype=np.float64)
            np.floor(c, out=c)
            c -= self.origin[k]
            np.clip(c, 0, self.shape[k] - 1, out=c)
            if index is None:
                index = c
            else:
                index *= self.shape[k]
                index += c
        assert index is not None
        return np.take(self.marked, index.astype(np.intp))

"""The compiled loop of :meth:`VisibleFaces.decide_image` (``visible_face.c``): its arguments.

What it is for: the C loop reads a ``VisibleFaces``' tables (per face, per group, per watched
edge, the two cell tables and the near cells' grid) as contiguous arrays of fixed dtypes, in
the order of the C file's ``enum Table``; they are laid out once per ``VisibleFaces``
(:func:`loop_tables`) and handed over with each camera's pixels (:func:`decide_pixels`).
What it must not do: decide anything (the C loop does, the same as numpy's passes).
"""

from __future__ import annotations

from types import ModuleType
from typing import Any, Protocol

import numpy as np

from povagent.generate.cell_table import CellMask, CellTable
from povagent.generate.face_groups import BuiltFaces, FaceRows


class PackedFaces(BuiltFaces, Protocol):
    """What :func:`loop_tables` reads of a built ``VisibleFaces``, beyond what
    :meth:`FaceRows.of` reads (:class:`~povagent.generate.face_groups.BuiltFaces`)."""

    @property
    def faces(self) -> CellTable: ...
    @property
    def mixed(self) -> np.ndarray: ...
    @property
    def watched(self) -> CellTable: ...
    @property
    def edge_across(self) -> np.ndarray: ...
    @property
    def near_cells(self) -> CellMask | None: ...


#: The loop's tables and numbers: built once per ``VisibleFaces``.
LoopTables = tuple[tuple[np.ndarray, ...], tuple[Any, ...]]


def loop_tables(faces: PackedFaces, rows: FaceRows, cell: float, edge_cell: float, margin: float, tolerance: float) -> LoopTables:
    """The arrays (in ``enum Table``'s order) and the numbers (the near cells' grid, the cell
    sizes' inverses as ``cell_table.cell`` computes them, the edge margin and the containment
    tolerance) the C loop reads."""

    def rows_of(x: np.ndarray, dtype: type) -> np.ndarray:
        return np.ascontiguousarray(x, dtype=dtype)

    f8, i8, u1 = np.float64, np.int64, np.uint8
    mask = faces.near_cells
    arrays = (
        rows_of(faces.group, i8),
        rows_of(rows.plane, f8),
        holding_rows(rows),
        rows_of(rows.group_watching, u1),
        rows_of(rows.overlapped, u1),
        rows_of(rows.outline, np.int32),
        rows_of(faces.group_normal.T, f8),
        rows_of(faces.group_offset, f8),
        rows_of(rows.box, f8),
        rows_of(faces.watching, u1),
        rows_of(faces.faces.keys, i8),
        rows_of(faces.faces.starts, i8),
        rows_of(faces.faces.items, i8),
        rows_of(faces.mixed, u1),
        rows_of(faces.watched.keys, i8),
        rows_of(faces.watched.starts, i8),
        rows_of(faces.watched.items, i8),
        # each watched edge's line, direction and extent side by side (gathered together)
        np.ascontiguousarray(np.concatenate([rows.line.T, rows.along.T, np.zeros((rows.line.shape[1], 1))], axis=1), dtype=f8),
        rows_of(faces.edge_across, i8),
        # (8 cells a byte: the grid's lookups stay in the cache)
        np.packbits(mask.marked, bitorder="little") if mask is not None else np.zeros(0, dtype=u1),
    )
    grid = (*(float(v) for v in mask.origin), *mask.shape, True, 1.0 / mask.size) if mask is not None else (0.0, 0.0, 0.0, 1, 1, 1, False, 1.0)
    return arrays, (*grid, 1.0 / cell, 1.0 / edge_cell, margin, tolerance)


def holding_rows(rows: FaceRows) -> np.ndarray:
    """(F, 16): each face's numbers of the containment test side by side (a face's are gathered
    together): its own normal, 1.0 where it is open (not a closed solid's) else 0.0, and its 3
    inward edge normals and offsets."""
    count = len(rows.open)
    out = np.empty((count, 16))
    out[:, :3] = rows.own.T
    out[:, 3] = rows.open
    out[:, 4:] = rows.edges.transpose(2, 0, 1).reshape(count, 12)
    return out


def fits(tri: np.ndarray, origin: np.ndarray, directions: np.ndarray, height: int, width: int) -> bool:
    """Whether the loop reads these pixels as they are: float32 (3, height * width) directions
    (as the renderer makes them; another dtype takes numpy's path), one origin, 64-bit indices;
    the triangles int32 (embree's, read as they are) or any integers within int32's range below
    (the loop keeps the faces shown as int32: a lower "no hit" would not survive it)."""
    return (
        isinstance(directions, np.ndarray)
        and directions.dtype == np.float32
        and directions.shape == (3, height * width)
        and np.shape(tri) == (height * width,)
        and np.size(origin) == 3
        and np.dtype(np.intp).itemsize == 8
        and (np.asarray(tri).dtype == np.int32 or not np.size(tri) or int(np.min(tri)) >= -(2**31))
    )


def decide_pixels(
    loop: ModuleType,
    tables: LoopTables,
    tri: np.ndarray,
    origin: np.ndarray,
    directions: np.ndarray,
    height: int,
    width: int,
    want_distance: bool,
    skip: bool,
    narrow: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """The loop's decision for one camera's pixels (:func:`fits`): the face shown and (if
    wanted, else ``None``) its distance, per pixel: intp and float64, or with ``narrow`` int32
    and float32 (the float64's rounding), written so by the loop."""
    count = height * width
    shown = np.empty(count, dtype=np.int32 if narrow else np.intp)
    t = np.empty(count if want_distance else 0, dtype=np.float32 if narrow else np.float64)
    o = np.asarray(origin, dtype=np.float64).ravel()
    arrays, numbers = tables
    embree = isinstance(tri, np.ndarray) and tri.dtype == np.int32  # read as it is
    pixel_tri = np.ascontiguousarray(tri) if embree else np.ascontiguousarray(tri, dtype=np.intp)
    rays = np.ascontiguousarray(directions)
    loop.decide_image(arrays, numbers, pixel_tri, (float(o[0]), float(o[1]), float(o[2])), rays, height, width, want_distance, skip, shown, t)
    return shown, t if want_distance else None


def as_asked(shown: np.ndarray, t: np.ndarray | None, narrow: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """numpy's answer (intp faces, float64 distances) as ``VisibleFaces.decide_image`` was asked
    for it: as it is, or with ``narrow`` int32 and float32, as :func:`decide_pixels` writes them."""
    return (shown.astype(np.int32), None if t is None else t.astype(np.float32)) if narrow else (shown, t)

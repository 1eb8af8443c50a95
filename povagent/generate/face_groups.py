"""Coplanar face groups, their overlaps and their creases: the geometry :class:`VisibleFaces`
is built from, once per mesh.

What it is for: :mod:`povagent.generate.visible_face` decides per ray which face a pixel shows;
it needs to know which faces lie in one plane and touch (a group), where differently looking
faces of a group overlap, and which edges two groups share (creases). Those are worked out here
from the float32 vertices embree reads, in float64 with IEEE operations only (+, -, *, /, sqrt,
comparisons), so they are the same on every CPU; and the per-face numbers the decisions gather,
laid out in rows (:class:`FaceRows`). What it must not do: look at rays or pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

#: Two faces are coplanar when their unit normals agree to this (|dot| >= 1 - this) ...
PARALLEL_TOLERANCE = 1e-9
#: ... and their planes are this close (metres).
PLANE_TOLERANCE = 1e-5
#: A hit point within this distance (metres) outside a triangle's edge still counts as inside:
#: more than embree's float32 error over a house (a few micrometres), far below a pixel.
CONTAINS_TOLERANCE = 1e-5


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) float64 arrays, with IEEE products and differences only."""
    # Laid out by hand (the formatter is told to skip it): the x, y and z components one per
    # row, as the cross product is written, so a wrong index stands out.
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)  # fmt: skip


def dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (n, 3) arrays, summed x, y, z in that order."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def unit(v: np.ndarray) -> np.ndarray:
    """Each row of ``v`` divided by its length (a zero row left as it is)."""
    length = np.sqrt(dot3(v, v))
    return v / np.where(length > 0, length, 1.0)[:, None]


def coplanar_touching_pairs(normal: np.ndarray, offset: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair (i, j), i != j, of faces in one plane (either side) whose grown boxes overlap.

    Two such faces' offsets differ by at most ``PLANE_TOLERANCE`` in absolute value (either
    side: ``|a - b|`` and ``|a + b|`` are both at least ``||a| - |b||``), so only faces close in
    ``|offset|`` (sorted, a window of twice the tolerance) are compared."""
    size = np.abs(offset)
    order = np.argsort(size, kind="stable")
    ranked = size[order]
    stop = np.searchsorted(ranked, ranked + 2 * PLANE_TOLERANCE, side="right")
    span = stop - np.arange(len(order)) - 1  # later faces within the window of each
    first = np.repeat(np.arange(len(order)), span)
    later = np.arange(len(first)) - np.repeat(np.cumsum(span) - span, span) + first + 1
    i, j = order[first], order[later]
    keep = np.ones(len(i), dtype=bool)
    for k in range(3):
        keep &= (lo[i, k] <= hi[j, k]) & (lo[j, k] <= hi[i, k])
    i, j = i[keep], j[keep]
    # either side: the generated meshes' floors are wound facing down
    cos = dot3(normal[i], normal[j])
    same = cos >= 1 - PARALLEL_TOLERANCE
    opposite = cos <= -(1 - PARALLEL_TOLERANCE)
    gap = np.where(same, np.abs(offset[i] - offset[j]), np.abs(offset[i] + offset[j]))
    keep = (same | opposite) & (gap <= PLANE_TOLERANCE)
    i, j = i[keep].astype(np.int64), j[keep].astype(np.int64)
    return np.concatenate([i, j]), np.concatenate([j, i])


def _apart(v: np.ndarray, faces: np.ndarray, own: np.ndarray, lf: np.ndarray, rf: np.ndarray) -> np.ndarray:
    """Per coplanar pair (lf, rf): whether the two triangles' areas do not overlap (an axis
    in their plane separates them, within the tolerance: faces sharing an edge are apart)."""
    apart = np.zeros(len(lf), dtype=bool)
    if not len(lf):
        return apart
    tris = [v[faces[lf]], v[faces[rf]]]  # (n, 3 corners, 3)
    for which, normal in ((0, own[lf]), (1, own[rf])):
        corners = tris[which]
        for k in range(3):
            axis = unit(cross(normal, corners[:, (k + 1) % 3] - corners[:, k]))
            a = tris[0][:, :, 0] * axis[:, None, 0] + tris[0][:, :, 1] * axis[:, None, 1] + tris[0][:, :, 2] * axis[:, None, 2]
            b = tris[1][:, :, 0] * axis[:, None, 0] + tris[1][:, :, 1] * axis[:, None, 1] + tris[1][:, :, 2] * axis[:, None, 2]
            apart |= (a.max(axis=1) <= b.min(axis=1) + CONTAINS_TOLERANCE) | (b.max(axis=1) <= a.min(axis=1) + CONTAINS_TOLERANCE)
    return apart


def overlapped_sides(
    v: np.ndarray, faces: np.ndarray, own: np.ndarray, closed: np.ndarray, looks: np.ndarray, left: np.ndarray, right: np.ndarray
) -> np.ndarray:
    """(F, 2): per side of each face (0: seen against its normal, 1: along it), whether a
    differently looking coplanar face, seen from that side too, overlaps its area."""
    differs = looks[left] != looks[right]
    lf, rf = left[differs], right[differs]
    out = np.zeros((len(faces), 2), dtype=bool)
    if not len(lf):
        return out
    apart = _apart(v, faces, own, lf, rf)
    aligned = dot3(own[lf], own[rf]) > 0
    for side in (0, 1):
        # a ray against f's normal meets the rival's front where the two face one way
        rival_seen = ~closed[rf] | (aligned if side == 0 else ~aligned)
        face_seen = ~closed[lf] if side == 1 else np.ones(len(lf), dtype=bool)
        hit = ~apart & rival_seen & face_seen
        out[lf[hit], side] = True
    return out


def groups_across_edges(v: np.ndarray, faces: np.ndarray, group: np.ndarray, looks: np.ndarray, by_look: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(F, 3, 2): for each face's edge k (from corner k to k + 1), the groups of up to two other
    faces with an edge between the same two points, where their group is not the face's (-1;
    ``by_look``: nor their look);
    and (F, 3): whether every other face on the edge is of the face's group and look (and
    there is one: the edge lies inside a region of one look)."""
    _, position = np.unique(v, axis=0, return_inverse=True)
    corner = position.ravel()[faces]
    ends = np.stack([corner, np.roll(corner, -1, axis=1)], axis=-1)  # (F, 3, 2)
    edge_id = np.unique(np.sort(ends, axis=-1).reshape(-1, 2), axis=0, return_inverse=True)[1].ravel()
    owner = np.repeat(np.arange(len(faces)), 3)
    order = np.lexsort((owner, edge_id))
    edge_sorted, owner_sorted = edge_id[order], owner[order]
    across = np.full((len(faces) * 3, 2), -1, dtype=np.int64)
    internal = np.zeros(len(faces) * 3, dtype=bool)
    starts = np.flatnonzero(np.r_[True, edge_sorted[1:] != edge_sorted[:-1]])
    stops = np.r_[starts[1:], len(edge_sorted)]
    for s, e in zip(starts.tolist(), stops.tolist()):
        if e - s < 2:
            continue
        sharing = owner_sorted[s:e].tolist()
        for slot in order[s:e].tolist():
            me = slot // 3
            others = [f for f in sharing if f != me]
            crossing = [int(group[f]) for f in others if group[f] != group[me] and (not by_look or looks[f] != looks[me])][:2]
            across[slot, : len(crossing)] = crossing
            internal[slot] = all(group[f] == group[me] and looks[f] == looks[me] for f in others)
    return across.reshape(len(faces), 3, 2), internal.reshape(len(faces), 3)


def inward_edges(normal: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each face's inward unit edge normals in its plane (F, 3, 3) and their offsets (F, 3): a
    point x lies within distance s inside edge k where ``m_k . x - offset_k = s``."""
    starts = (a, b, c)
    edges = np.empty((len(a), 3, 3))
    offsets = np.empty((len(a), 3))
    for k, (p, q) in enumerate(((a, b), (b, c), (c, a))):
        m = unit(cross(normal, q - p))
        edges[:, k] = m
        offsets[:, k] = dot3(m, starts[k])
    return edges, offsets


def group_boxes(
    corners: tuple[np.ndarray, np.ndarray, np.ndarray], own: np.ndarray, group: np.ndarray, normal: np.ndarray, offset: np.ndarray, near: float
) -> np.ndarray:
    """(G, 6): per group, the low x, y, z and high x, y, z of a box that holds every point of the
    group's plane (``normal``, ``offset``) that a face of the group holds (within
    ``CONTAINS_TOLERANCE``: ``VisibleFaces._highest_holding``) or that lies within ``near`` of
    one of its edges (``VisibleFaces._near_watched``). A point outside needs neither test.

    Why the box is large enough, per face f (the group's box is the union of its faces'):
    the points f holds are those within ``CONTAINS_TOLERANCE`` outside each edge's line, a
    prism along f's normal over f's triangle grown by ``reach`` = tolerance / sin(half the
    sharpest corner's angle) (the grown triangle's corners move out along the bisectors); the
    points near an edge (at most ``near`` across its line and past its ends) are a prism over a
    rectangle within ``2 * near`` of f. With ``R`` the larger of the two, such a point projects
    onto f's plane inside f's box grown by ``R``, and lies off that plane by its own plane's
    distance from the group's there: at most ``(dev + R) / cos``, ``dev`` the farthest of f's
    corners from the group's plane and ``cos`` the cosine between the two normals (an affine
    function's extreme over the grown triangle is at a corner, which is within ``R`` of one of
    f's). A degenerate face (a zero edge or no normal) holds every point of its plane: its
    group's box is infinite."""
    a, b, c = corners
    sharpest = np.ones(len(a))
    degenerate = dot3(own, own) == 0
    for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
        u, w = q - p, r - p
        degenerate |= (dot3(u, u) == 0) | (dot3(w, w) == 0)
        cos = dot3(unit(u), unit(w))
        sharpest = np.minimum(sharpest, np.sqrt(np.maximum(0.5 - 0.5 * cos, 0.0)))
    reach = np.divide(CONTAINS_TOLERANCE, sharpest, out=np.full(len(a), np.inf), where=sharpest > 0)
    grown_by = np.maximum(reach, 2 * near)
    gn, go = normal[group], offset[group]
    dev = np.maximum(np.maximum(np.abs(dot3(gn, a) - go), np.abs(dot3(gn, b) - go)), np.abs(dot3(gn, c) - go))
    cos_planes = np.abs(dot3(gn, own))
    off_plane = np.divide(dev + grown_by, cos_planes, out=np.full(len(a), np.inf), where=cos_planes > 0.5)
    grow = grown_by + off_plane + 1e-6  # (and a micrometre for the rounding of these sums)
    grow[degenerate] = np.inf
    lo = np.minimum(np.minimum(a, b), c) - grow[:, None]
    hi = np.maximum(np.maximum(a, b), c) + grow[:, None]
    box = np.empty((len(normal), 6))
    box[:, :3], box[:, 3:] = np.inf, -np.inf
    np.minimum.at(box[:, :3], group, lo)
    np.maximum.at(box[:, 3:], group, hi)
    return box


class BuiltFaces(Protocol):
    """What :meth:`FaceRows.of` reads of a built ``VisibleFaces`` (named by its fields, so this
    module, below ``visible_face``, does not import it)."""

    @property
    def group(self) -> np.ndarray: ...
    @property
    def group_normal(self) -> np.ndarray: ...
    @property
    def group_offset(self) -> np.ndarray: ...
    @property
    def own_normal(self) -> np.ndarray: ...
    @property
    def closed(self) -> np.ndarray: ...
    @property
    def edges(self) -> np.ndarray: ...
    @property
    def edge_offsets(self) -> np.ndarray: ...
    @property
    def watching(self) -> np.ndarray: ...
    @property
    def overlapped(self) -> np.ndarray: ...
    @property
    def outline(self) -> np.ndarray: ...
    @property
    def group_box(self) -> np.ndarray: ...
    @property
    def edge_line(self) -> np.ndarray: ...
    @property
    def edge_along(self) -> np.ndarray: ...


@dataclass(frozen=True)
class FaceRows:
    """The per-face and per-edge numbers the decisions gather, one contiguous row per
    component: a gather from a row is several times faster than from a column of an (F, 3)
    array, and the values (hence every product and sum) are the same."""

    own: np.ndarray  # (3, F): each face's own normal
    open: np.ndarray  # (F,): not a closed solid's face (met from either side)
    edges: np.ndarray  # (3 edges, 4, F): inward edge normal x, y, z and offset
    plane: np.ndarray  # (4, F): each face's group plane, normal x, y, z and offset
    group_watching: np.ndarray  # (F,): the face's group has a watched edge
    overlapped: np.ndarray  # (2 * F,): ``overlapped`` flat, face * 2 + side
    overlapped_any: np.ndarray  # (F,): overlapped from either side
    outline: np.ndarray  # (F,) int32: ``outline``
    outline_is_group: bool
    box: np.ndarray  # (6, G): ``group_box``
    line: np.ndarray  # (4, E): each watched edge's in-plane line
    along: np.ndarray  # (5, E): each watched edge's direction and extent

    @classmethod
    def of(cls, faces: BuiltFaces) -> FaceRows:
        """The rows of a built ``VisibleFaces``."""
        plane = np.concatenate([faces.group_normal, faces.group_offset[:, None]], axis=1)[faces.group]
        edges = np.concatenate([faces.edges, faces.edge_offsets[:, :, None]], axis=2)  # (F, 3, 4)
        return cls(
            np.ascontiguousarray(faces.own_normal.T),
            ~faces.closed,
            np.ascontiguousarray(edges.transpose(1, 2, 0)),
            np.ascontiguousarray(plane.T),
            faces.watching[faces.group],
            np.ascontiguousarray(faces.overlapped).ravel(),
            np.asarray(faces.overlapped.any(axis=1)),
            faces.outline.astype(np.int32),
            bool(np.array_equal(faces.outline, faces.group)),
            np.ascontiguousarray(faces.group_box.T),
            np.ascontiguousarray(faces.edge_line.T),
            np.ascontiguousarray(faces.edge_along.T),
        )

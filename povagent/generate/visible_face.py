"""The face a ray sees and how far away it is, decided the same way on every machine.

What it is for: embree finds which triangle a ray hits first, but it runs kernels chosen for
the CPU at hand (SSE2, AVX, AVX2, AVX-512), whose floating-point results differ in their last
bits: the distance it reports differs for nearly every pixel from one CPU to another, and
where two faces lie in one plane (a mattress flush with its frame, two halves of a wall) or a
ray grazes an edge, the face it reports is decided by that noise. Left as it was, a generated
set's PNGs differed between an AVX2 and an AVX-512 machine. Here embree's answer is only a
candidate:

* the distance is recomputed from the plane of the face's **group** (faces in one plane whose
  boxes touch, joined transitively), in float64 with IEEE operations only, so every face of a
  group gives the same distance and the same shading normal;
* where faces of a group that look different (colour, material, object, room light) overlap,
  or a hit lies near such a face's edge, the face shown is the one of highest index among the
  group's faces holding the hit point (within ``CONTAINS_TOLERANCE``);
* for a camera's pixels (:meth:`VisibleFaces.decide_image`), where the 3x3 neighbourhood shows
  more than one group, or the hit lies near an edge where its group meets another (a crease),
  the pixel shows the nearest of those groups whose faces hold its ray: a ray that grazes an
  edge reports the face in front on one CPU and the one behind on another, but its neighbours
  (or the crease) name the face in front on every CPU, and the exact test decides alike.

A closed solid's face (every box, prism and sphere) is met only from outside; a floor or a
ceiling (a lone quad) from either side. Faces near a point are found through tables keyed by
(group, ``CELL``-sized cell). What stays machine-dependent: a sliver thinner than a pixel that
no neighbour shows and no crease leads to, and shadow rays grazing an edge (embree decides
those alone); measured in ``benchmarks/bench_render_isa.py``, see
``docs/explanation/reproducibility.md``. What it must not do: call a numpy function whose
result depends on the CPU (transcendentals, BLAS): it uses +, -, *, /, sqrt and comparisons,
element by element.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from povagent.generate.cell_table import CellMask, CellTable, boxes_keys, cell, key_of, unique_pairs

#: Two faces are coplanar when their unit normals agree to this (|dot| >= 1 - this) ...
PARALLEL_TOLERANCE = 1e-9
#: ... and their planes are this close (metres).
PLANE_TOLERANCE = 1e-5
#: A hit point within this distance (metres) outside a triangle's edge still counts as inside:
#: more than embree's float32 error over a house (a few micrometres), far below a pixel.
CONTAINS_TOLERANCE = 1e-5
#: Faces whose boxes, grown by this (metres), overlap touch (so that two faces that both hold
#: a point within the tolerance always touch).
TOUCH_MARGIN = 4 * CONTAINS_TOLERANCE
#: A hit within this distance (metres) of a watched edge is decided exactly.
EDGE_MARGIN = 4 * CONTAINS_TOLERANCE
#: Side of the cubic cells (metres) of the faces' lookup table ...
CELL = 0.25
#: ... and of the watched edges' (finer: a cell lists the few edges passing through it).
EDGE_CELL = 0.0625


@dataclass(frozen=True)
class VisibleFaces:
    """A mesh's face groups, planes and lookup tables, built once per mesh.

    ``group``: each face's group; ``group_normal``/``group_offset``: each group's plane
    ``n . x = offset`` (its lowest-index face's); ``own_normal``: each face's own (winding)
    normal; ``closed``: faces of closed solids; ``edges``/``edge_offsets``: each face's inward
    in-plane edge normals and offsets (the containment test); ``faces``: per (group, cell),
    the group's faces reaching the cell, highest index first; ``mixed``: per such key, whether
    its faces do not all look alike; ``overlapped``: (F, 2) whether a differently looking
    coplanar face seen from the same side (0: rays against the face's normal, 1: along it)
    overlaps the face; ``watched``: per (group, cell), the edges near which a hit is decided
    exactly (creases, and every edge of a face in a mixed cell); ``edge_*``: those edges'
    in-plane line (normal, offset), direction and extent, and the groups across a crease;
    ``outline``: what tells two pixels apart (each face's group, or its look ``by_look``);
    ``watching``: the groups with a watched edge at all; ``near_cells``: the ``EDGE_CELL``
    cells (any group) a watched edge may be near.
    """

    group: np.ndarray
    group_normal: np.ndarray
    group_offset: np.ndarray
    own_normal: np.ndarray
    closed: np.ndarray
    edges: np.ndarray
    edge_offsets: np.ndarray
    faces: CellTable
    mixed: np.ndarray
    overlapped: np.ndarray
    watched: CellTable
    edge_line: np.ndarray
    edge_along: np.ndarray
    edge_across: np.ndarray
    outline: np.ndarray
    watching: np.ndarray
    near_cells: CellMask | None

    @classmethod
    def build(cls, vertices: np.ndarray, faces: np.ndarray, looks: np.ndarray, closed: np.ndarray | None = None, by_look: bool = False) -> VisibleFaces:
        """From float32 ``vertices`` (as embree reads them), (F, 3) ``faces``, one integer
        ``looks`` per face (equal where two faces shade alike) and whether each face bounds a
        closed solid, turned outward (no ray from outside meets it from behind: a wall's foot,
        in the floor's plane, is never a floor pixel's face); default: none does.

        ``by_look``: only the look a pixel shows matters, not the face (an instance mask, whose
        look is the object): a pixel is decided between groups only where its neighbours' looks
        differ or it lies near a crease to another look. A rendered frame needs the face
        (two faces of a box shade differently however alike their colour): the default."""
        v = np.asarray(vertices, dtype=np.float32).astype(np.float64)
        count = len(faces)
        closed = np.zeros(count, dtype=bool) if closed is None else np.asarray(closed, dtype=bool)
        a, b, c = (v[faces[:, i]] for i in range(3))
        own = _unit(_cross(b - a, c - a))
        offset = _dot3(own, a)
        lo = np.minimum(np.minimum(a, b), c) - TOUCH_MARGIN
        hi = np.maximum(np.maximum(a, b), c) + TOUCH_MARGIN
        left, right = _coplanar_touching_pairs(own, offset, lo, hi)
        graph = coo_matrix((np.ones(len(left)), (left, right)), shape=(count, count))
        _, group = connected_components(graph, directed=False)
        first = np.full(group.max() + 1 if count else 0, count, dtype=np.int64)
        np.minimum.at(first, group, np.arange(count))
        edges, edge_offsets = _inward_edges(own, a, b, c)
        # every face under (its group, each cell its grown box reaches), the highest first
        key, item = boxes_keys(group, cell(lo, CELL), cell(hi, CELL))
        table = CellTable.build([key], [item], order_by=-np.arange(count))
        look = looks[table.items]
        sizes = np.diff(table.starts)
        differs = look != np.repeat(look[table.starts[:-1]], sizes)
        mixed = np.zeros(len(table.keys), dtype=bool)
        np.logical_or.at(mixed, np.repeat(np.arange(len(table.keys)), sizes), differs)
        overlapped = _overlapped_sides(v, faces, own, closed, looks, left, right)
        # watched edges: creases, and every edge of a face listed under a mixed key
        across, internal = _groups_across_edges(v, faces, group, looks, by_look)
        in_mixed = np.zeros(count, dtype=bool)
        in_mixed[table.items[np.repeat(mixed, sizes)]] = True
        # (an edge inside a region of one look, a quad's diagonal, decides nothing)
        watch = (across >= 0).any(axis=2) | (in_mixed[:, None] & ~internal)
        wf, we = np.nonzero(watch)
        p, q = v[faces[wf, we]], v[faces[wf, (we + 1) % 3]]
        line = _unit(_cross(own[wf], q - p))
        along = _unit(q - p)
        edge_line = np.concatenate([line, _dot3(line, p)[:, None]], axis=1)
        edge_along = np.concatenate([along, _dot3(along, p)[:, None], _dot3(along, q)[:, None]], axis=1)
        grow = EDGE_MARGIN + TOUCH_MARGIN
        elo, ehi = cell(np.minimum(p, q) - grow, EDGE_CELL), cell(np.maximum(p, q) + grow, EDGE_CELL)
        ekey, eitem = boxes_keys(group[wf], elo, ehi)
        watched = CellTable.build([ekey], [eitem])
        outline = looks if by_look else group
        watching = np.zeros(len(first), dtype=bool)
        watching[group[wf]] = True
        return cls(
            group,
            own[first],
            offset[first],
            own,
            closed,
            edges,
            edge_offsets,
            table,
            mixed,
            overlapped,
            watched,
            edge_line,
            edge_along,
            across[wf, we],
            np.asarray(outline, dtype=np.int64),
            watching,
            CellMask.build(elo, ehi, EDGE_CELL),
        )

    @property
    def face_normals(self) -> np.ndarray:
        """(F, 3) float64: the normal each face is shaded with, its group's plane normal."""
        return self.group_normal[self.group]

    # -- any rays ---------------------------------------------------------------------------
    def decide(self, tri: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The face shown and the float64 distance along each ray, from embree's ``tri``
        (-1: no hit; then the distance is inf). ``origins``: (3,) for one origin or (3, N)
        rows; ``directions``: (3, N) rows."""
        o = np.asarray(origins, dtype=np.float64)
        d = tuple(np.asarray(r, dtype=np.float64) for r in directions)
        shown, t, _, _ = self._decide(tri, o, d)
        assert t is not None
        return shown, t

    def _decide(
        self,
        tri: np.ndarray,
        o: np.ndarray,
        d: tuple[np.ndarray, ...],
        want_distance: bool = True,
        near: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]:
        """:meth:`decide` (the distances only if wanted), and the (ray, group) pairs of groups
        across a crease near each hit. ``near``: whether each hit lies in one of ``near_cells``
        (one that does not is near no watched edge: its exact tests are skipped)."""
        hit = tri >= 0
        face = np.where(hit, tri, 0)
        shown = tri.copy()
        # which side of its face each ray meets (0: against the face's normal)
        facing = np.take(self.own_normal[:, 0], face) * d[0]
        facing += np.take(self.own_normal[:, 1], face) * d[1]
        facing += np.take(self.own_normal[:, 2], face) * d[2]
        side = (facing >= 0).astype(np.intp)
        # only a hit in a group with a watched edge, or on a face a rival overlaps from that side,
        # can be decided otherwise
        watched = self.watching[self.group[face]]
        if near is not None:
            watched &= near
        examined = hit & (watched | self.overlapped[face, side])
        t: np.ndarray | None = None
        if want_distance:
            every = self._distance(self.group[face], o, d, np.arange(len(tri)))
            every[~hit] = np.inf
            rays = np.flatnonzero(examined & np.isfinite(every))  # (a parallel ray's t is inf)
            reach = every[rays]
            t = every
        else:
            rays = np.flatnonzero(examined)
            reach = self._distance(self.group[face[rays]], o, d, rays)
            rays, reach = rays[np.isfinite(reach)], reach[np.isfinite(reach)]
        point = _points(o, d, rays, reach)
        near_edge, crease_ray, crease_group = self._near_watched(self.group[tri[rays]], point)
        decide = np.flatnonzero(self.overlapped[tri[rays], side[rays]] | near_edge)
        if len(decide):
            at = self.faces.find(key_of(self.group[tri[rays[decide]]], [p[decide] for p in point], CELL))
            listed = at >= 0
            listed[listed] = self.mixed[at[listed]]
            pick = decide[listed]
            best = self._highest_holding(at[listed], [p[pick] for p in point], rays[pick], d)
            shown[rays[pick]] = np.where(best >= 0, best, tri[rays[pick]])
        return shown, t, rays[crease_ray], crease_group

    # -- a camera's pixels ------------------------------------------------------------------
    def decide_image(
        self, tri: np.ndarray, origin: np.ndarray, directions: np.ndarray, height: int, width: int, want_distance: bool = True, reach: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`decide` for the rays of one camera's pixels (row-major, one ``origin``), each
        pixel near another group (in its 3x3 neighbourhood or across a nearby crease) showing
        the nearest of the groups whose faces hold its ray; the distances ``None`` unless wanted.
        ``reach``: embree's float32 distances, to skip the exact tests of hits in no cell a
        watched edge reaches (the skip is decided on embree's numbers, so it may differ by CPU,
        but only for hits a cell or more from any watched edge, which the exact test leaves
        as they are)."""
        near = None
        if reach is not None and self.near_cells is not None:
            o32 = np.asarray(origin, dtype=np.float32)
            t32 = np.where(tri >= 0, reach, np.float32(0))
            near = self.near_cells.covers(*(o32[k] + np.asarray(directions[k], dtype=np.float32) * t32 for k in range(3)))
        o = np.asarray(origin, dtype=np.float64)
        d = tuple(np.asarray(r, dtype=np.float64) for r in directions)
        shown, t, crease_ray, crease_group = self._decide(tri, o, d, want_distance, near)
        face = np.maximum(shown, 0)
        seen = np.where(shown >= 0, self.outline[face], -1).reshape(height, width)
        outlined = np.pad(seen, 1, mode="edge")
        edge = np.zeros((height, width), dtype=bool)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                if dy or dx:
                    edge |= outlined[1 + dy : 1 + dy + height, 1 + dx : 1 + dx + width] != seen
        pixels = np.flatnonzero(edge.ravel())
        padded = np.pad(np.where(shown >= 0, self.group[face], -1).reshape(height, width), 1, mode="edge")
        if not len(pixels) and not len(crease_ray):
            return shown, t
        # candidates: the groups the 3x3 neighbourhood shows, those across a crease near the
        # hit, and those across a crease near where the ray meets a neighbour's group
        y, x = np.divmod(pixels, width)
        stride = width + 2
        around = padded.ravel()[((y + 1) * stride + x + 1)[:, None] + np.array([dy * stride + dx for dy in (-1, 0, 1) for dx in (-1, 0, 1)])]
        # each pixel's distinct groups, ascending (a sort of nine per row, not of them all)
        around.sort(axis=1)
        fresh = around >= 0
        fresh[:, 1:] &= around[:, 1:] != around[:, :-1]
        ray, cand = np.repeat(pixels, fresh.sum(axis=1)), around[fresh]
        if len(crease_ray):
            ray, cand = unique_pairs(np.concatenate([ray, crease_ray]), np.concatenate([cand, crease_group]))
        dist = self._distance(cand, o, d, ray)
        ahead = np.isfinite(dist) & (dist > 0)
        point = _points(o, d, ray[ahead], dist[ahead])
        _, extra_at, extra_group = self._near_watched(cand[ahead], point)
        if len(extra_at):
            ray, cand = unique_pairs(np.concatenate([ray, ray[ahead][extra_at]]), np.concatenate([cand, extra_group]))
            dist = self._distance(cand, o, d, ray)
        ahead = np.isfinite(dist) & (dist > 0)
        ray, cand, dist = ray[ahead], cand[ahead], dist[ahead]
        point = _points(o, d, ray, dist)
        at = self.faces.find(key_of(cand, point, CELL))
        face = np.full(len(ray), -1, dtype=np.int64)
        listed = np.flatnonzero(at >= 0)
        face[listed] = self._highest_holding(at[listed], [p[listed] for p in point], ray[listed], d)
        held = face >= 0
        ray, dist, face = ray[held], dist[held], face[held]
        # per pixel, the nearest holding group (a tie in distance: the higher face)
        order = np.lexsort((-face, dist, ray))
        ray, dist, face = ray[order], dist[order], face[order]
        first = np.ones(len(ray), dtype=bool)
        first[1:] = ray[1:] != ray[:-1]
        shown[ray[first]] = face[first]
        if t is not None:
            t[ray[first]] = dist[first]
        return shown, t

    # -- the exact tests --------------------------------------------------------------------
    def _distance(self, group: np.ndarray, o: np.ndarray, d: tuple[np.ndarray, ...], ray: np.ndarray) -> np.ndarray:
        """Distance along each ray (an index into ``d``'s rows) to its group's plane (inf where parallel)."""
        nx, ny, nz = (np.take(self.group_normal[:, k], group) for k in range(3))
        if o.ndim == 1:  # one origin: the plane's offset from it once per group
            n = self.group_normal
            across = np.take(self.group_offset - (n[:, 0] * o[0] + n[:, 1] * o[1] + n[:, 2] * o[2]), group)
        else:
            across = np.take(self.group_offset, group) - (nx * o[0][ray] + ny * o[1][ray] + nz * o[2][ray])
        along = nx * np.take(d[0], ray)
        along += ny * np.take(d[1], ray)
        along += nz * np.take(d[2], ray)
        return np.divide(across, along, out=np.full(len(group), np.inf), where=along != 0)

    def _near_watched(self, group: np.ndarray, point: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Which points lie within ``EDGE_MARGIN`` of a watched edge of their group, and the
        (point index, group) pairs of the groups across the creases they lie near."""
        near = np.zeros(len(group), dtype=bool)
        some = np.flatnonzero(self.watching[group])  # only groups with a watched edge are looked up
        at = self.watched.find(key_of(group[some], [p[some] for p in point], EDGE_CELL))
        listed = some[at >= 0]
        at = at[at >= 0]
        row, edge = self.watched.explode(at)
        row = listed[row]
        line, along = self.edge_line[edge], self.edge_along[edge]
        x = [p[row] for p in point]
        off = line[:, 0] * x[0] + line[:, 1] * x[1] + line[:, 2] * x[2] - line[:, 3]
        pos = along[:, 0] * x[0] + along[:, 1] * x[1] + along[:, 2] * x[2]
        close = (np.abs(off) < EDGE_MARGIN) & (pos > along[:, 3] - EDGE_MARGIN) & (pos < along[:, 4] + EDGE_MARGIN)
        near[row[close]] = True
        across = self.edge_across[edge[close]]  # (n, 2)
        pair_row = np.repeat(row[close], 2)
        pair_group = across.ravel()
        keep = pair_group >= 0
        return near, pair_row[keep], pair_group[keep]

    def _highest_holding(self, at: np.ndarray, point: list[np.ndarray], ray: np.ndarray, d: tuple[np.ndarray, ...]) -> np.ndarray:
        """Per entry, the highest-index face listed under its key whose triangle holds the
        point (within the tolerance) and that its ray can meet (a closed solid's face from
        outside only); -1 where none does."""
        row, g = self.faces.explode(at)
        n = self.own_normal[g]
        dr = [r[ray[row]] for r in d]
        inside = ~self.closed[g] | (n[:, 0] * dr[0] + n[:, 1] * dr[1] + n[:, 2] * dr[2] < 0)
        for e in range(3):
            m = self.edges[g, e]
            signed = m[:, 0] * point[0][row] + m[:, 1] * point[1][row] + m[:, 2] * point[2][row] - self.edge_offsets[g, e]
            inside &= signed >= -CONTAINS_TOLERANCE
        best = np.full(len(at), -1, dtype=np.int64)
        np.maximum.at(best, row[inside], g[inside])
        return best


# -- helpers ----------------------------------------------------------------------------------
def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) float64 arrays, with IEEE products and differences only."""
    # Laid out by hand (the formatter is told to skip it): the x, y and z components one per
    # row, as the cross product is written, so a wrong index stands out.
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)  # fmt: skip


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (n, 3) arrays, summed x, y, z in that order."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.sqrt(_dot3(v, v))
    return v / np.where(length > 0, length, 1.0)[:, None]


def _points(o: np.ndarray, d: tuple[np.ndarray, ...], ray: np.ndarray, dist: np.ndarray) -> list[np.ndarray]:
    """The points ``o + d * dist`` of the given rays, one array per coordinate."""
    return [(o[k] if o.ndim == 1 else o[k][ray]) + d[k][ray] * dist for k in range(3)]


def _coplanar_touching_pairs(normal: np.ndarray, offset: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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
    cos = _dot3(normal[i], normal[j])
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
            axis = _unit(_cross(normal, corners[:, (k + 1) % 3] - corners[:, k]))
            a = tris[0][:, :, 0] * axis[:, None, 0] + tris[0][:, :, 1] * axis[:, None, 1] + tris[0][:, :, 2] * axis[:, None, 2]
            b = tris[1][:, :, 0] * axis[:, None, 0] + tris[1][:, :, 1] * axis[:, None, 1] + tris[1][:, :, 2] * axis[:, None, 2]
            apart |= (a.max(axis=1) <= b.min(axis=1) + CONTAINS_TOLERANCE) | (b.max(axis=1) <= a.min(axis=1) + CONTAINS_TOLERANCE)
    return apart


def _overlapped_sides(
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
    aligned = _dot3(own[lf], own[rf]) > 0
    for side in (0, 1):
        # a ray against f's normal meets the rival's front where the two face one way
        rival_seen = ~closed[rf] | (aligned if side == 0 else ~aligned)
        face_seen = ~closed[lf] if side == 1 else np.ones(len(lf), dtype=bool)
        hit = ~apart & rival_seen & face_seen
        out[lf[hit], side] = True
    return out


def _groups_across_edges(v: np.ndarray, faces: np.ndarray, group: np.ndarray, looks: np.ndarray, by_look: bool = False) -> tuple[np.ndarray, np.ndarray]:
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


def _inward_edges(normal: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each face's inward unit edge normals in its plane (F, 3, 3) and their offsets (F, 3): a
    point x lies within distance s inside edge k where ``m_k . x - offset_k = s``."""
    starts = (a, b, c)
    edges = np.empty((len(a), 3, 3))
    offsets = np.empty((len(a), 3))
    for k, (p, q) in enumerate(((a, b), (b, c), (c, a))):
        m = _unit(_cross(normal, q - p))
        edges[:, k] = m
        offsets[:, k] = _dot3(m, starts[k])
    return edges, offsets

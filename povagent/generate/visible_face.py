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
(group, ``CELL``-sized cell). The work is kept to where it can change a decision, and every
shortcut is itself decided on the float64 numbers the tests use (never on embree's), so it
changes no pixel on any CPU (``tests/generate/test_visible_face.py`` holds the pixels equal to
testing everything): a hit in no cell of a watched edge skips the near-edge test (it would find
no edge to test); a candidate group whose ``group_box`` (:func:`~povagent.generate.face_groups.
group_boxes`) the ray meets outside is dropped (none of its faces could hold the point); an
outline pixel's candidates are tested nearest first, a farther one only where none nearer holds
the ray. What stays machine-dependent: a sliver thinner than a pixel that no neighbour shows and
no crease leads to, and shadow rays grazing an edge (embree decides those alone); measured in
``benchmarks/bench_render_isa.py``, see ``docs/explanation/reproducibility.md``. What it must
not do: call a numpy function whose result depends on the CPU (transcendentals, BLAS): it uses
+, -, *, /, sqrt and comparisons, element by element. A camera's pixels go through the compiled
loop ``visible_face.c`` where it was built (the same operations in the same order: the same
numbers), numpy's passes otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from povagent.generate.cell_table import CellMask, CellTable, boxes_keys, cell, key_of, unique_pairs
from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.face_groups import (
    CONTAINS_TOLERANCE,
    FaceRows,
    coplanar_touching_pairs,
    cross,
    dot3,
    group_boxes,
    groups_across_edges,
    inward_edges,
    overlapped_sides,
    unit,
)
from povagent.generate.visible_face_loop import LoopTables, as_asked, decide_pixels, fits, loop_tables

#: The compiled decision of a camera's pixels (``visible_face.c``), or ``None``: numpy's passes.
_LOOP = "_visible_face"
_COMPILED = compiled_loop(_LOOP)

#: The 3x3 neighbourhood of a pixel, row then column offsets.
_NINE_DY, _NINE_DX = np.repeat([-1, 0, 1], 3), np.tile([-1, 0, 1], 3)
_ALL, _HEAD, _TAIL = slice(None), slice(1, None), slice(None, -1)
#: A pixel's neighbours in four directions (left, up, up-left, up-right), as the
#: slices of an image at the pixels and at their neighbours (the other four are the reverse).
_PAIRS = (((_ALL, _HEAD), (_ALL, _TAIL)), ((_HEAD, _ALL), (_TAIL, _ALL)), ((_HEAD, _HEAD), (_TAIL, _TAIL)), ((_HEAD, _TAIL), (_TAIL, _HEAD)))
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
    cells (any group) a watched edge may be near; ``group_box``: (G, 6) per group, a box
    outside which none of its faces holds a point and no point is near its edges.
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
    group_box: np.ndarray
    _rows: FaceRows = field(init=False, repr=False, compare=False)
    _loop_tables: list[LoopTables] = field(init=False, repr=False, compare=False, default_factory=list)  # built on first use

    def __post_init__(self) -> None:
        object.__setattr__(self, "_rows", FaceRows.of(self))

    def __getstate__(self) -> dict[str, object]:
        return {**self.__dict__, "_loop_tables": []}  # (the loop's tables: laid out again where used, not pickled)

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
        own = unit(cross(b - a, c - a))
        offset = dot3(own, a)
        lo = np.minimum(np.minimum(a, b), c) - TOUCH_MARGIN
        hi = np.maximum(np.maximum(a, b), c) + TOUCH_MARGIN
        left, right = coplanar_touching_pairs(own, offset, lo, hi)
        graph = coo_matrix((np.ones(len(left)), (left, right)), shape=(count, count))
        _, group = connected_components(graph, directed=False)
        first = np.full(group.max() + 1 if count else 0, count, dtype=np.int64)
        np.minimum.at(first, group, np.arange(count))
        edges, edge_offsets = inward_edges(own, a, b, c)
        # every face under (its group, each cell its grown box reaches), the highest first
        key, item = boxes_keys(group, cell(lo, CELL), cell(hi, CELL))
        table = CellTable.build([key], [item], order_by=-np.arange(count))
        look = looks[table.items]
        sizes = np.diff(table.starts)
        differs = look != np.repeat(look[table.starts[:-1]], sizes)
        mixed = np.zeros(len(table.keys), dtype=bool)
        np.logical_or.at(mixed, np.repeat(np.arange(len(table.keys)), sizes), differs)
        overlapped = overlapped_sides(v, faces, own, closed, looks, left, right)
        # watched edges: creases, and every edge of a face listed under a mixed key
        across, internal = groups_across_edges(v, faces, group, looks, by_look)
        in_mixed = np.zeros(count, dtype=bool)
        in_mixed[table.items[np.repeat(mixed, sizes)]] = True
        # (an edge inside a region of one look, a quad's diagonal, decides nothing)
        watch = (across >= 0).any(axis=2) | (in_mixed[:, None] & ~internal)
        wf, we = np.nonzero(watch)
        p, q = v[faces[wf, we]], v[faces[wf, (we + 1) % 3]]
        line = unit(cross(own[wf], q - p))
        along = unit(q - p)
        edge_line = np.concatenate([line, dot3(line, p)[:, None]], axis=1)
        edge_along = np.concatenate([along, dot3(along, p)[:, None], dot3(along, q)[:, None]], axis=1)
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
            group_boxes((a, b, c), own, group, own[first], offset[first], EDGE_MARGIN),
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
        skip: bool = False,
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]:
        """:meth:`decide` (the distances only if wanted), and the (ray, group) pairs of groups
        across a crease near each hit. ``skip``: the exact tests of hits in none of
        ``near_cells`` are skipped (they would find no watched edge to test)."""
        hit = tri >= 0
        face = np.where(hit, tri, 0)
        shown = tri.copy()
        rows = self._rows
        # only a hit in a group with a watched edge, or on a face a rival overlaps from the side
        # the ray meets, can be decided otherwise
        examined = np.take(rows.group_watching, face)
        near_cells = self.near_cells if skip else None
        every: np.ndarray | None = None
        if want_distance or near_cells is not None:
            every = self._face_distance(face, o, d)
            every[~hit] = np.inf
            finite = np.isfinite(every)  # (a parallel ray's t is inf)
        if near_cells is not None and every is not None:
            # each hit, as the exact tests compute it: one in no cell of a watched edge has no
            # key in the watched table, so the tests would leave it as it is
            at = np.where(finite, every, 0.0)
            hits = [o[k] + d[k] * at for k in range(3)]
            examined &= near_cells.covers(*hits)
        rival = np.flatnonzero(np.take(rows.overlapped_any, face) & ~examined)
        examined[rival] = np.take(rows.overlapped, face[rival] * 2 + self._side(face[rival], d, rival))
        examined &= hit
        if every is not None:
            rays = np.flatnonzero(examined & finite)
            reach = every[rays]
            point = [h[rays] for h in hits] if near_cells is not None else _points(o, d, rays, reach)
        else:
            rays = np.flatnonzero(examined)
            reach = self._face_distance(face[rays], o, d, rays)
            rays, reach = rays[np.isfinite(reach)], reach[np.isfinite(reach)]
            point = _points(o, d, rays, reach)
        t = every if want_distance else None
        near_edge, crease_ray, crease_group = self._near_watched(self.group[tri[rays]], point)
        overlapped = np.take(rows.overlapped, tri[rays] * 2 + self._side(tri[rays], d, rays))
        decide = np.flatnonzero(overlapped | near_edge)
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
        self, tri: np.ndarray, origin: np.ndarray, directions: np.ndarray, height: int, width: int, want_distance: bool = True, skip: bool = False,
        narrow: bool = False,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`decide` for the rays of one camera's pixels (row-major, one ``origin``), each
        pixel near another group (in its 3x3 neighbourhood or across a nearby crease) showing
        the nearest of the groups whose faces hold its ray; the distances ``None`` unless wanted.
        ``skip``: the exact tests of hits in no cell of a watched edge (``near_cells``, looked up
        with the float64 hit the tests would use) are skipped: they would find no edge to test.
        float32 directions (the renderer's) go through the compiled loop where it was built. The
        faces are intp and the distances float64, or with ``narrow`` int32 and float32 (the
        float64's rounding: what the renderer's depth and shading use, half the memory)."""
        if _COMPILED is not None and fits(tri, origin, directions, height, width):
            if not self._loop_tables:
                self._loop_tables.append(loop_tables(self, self._rows, CELL, EDGE_CELL, EDGE_MARGIN, CONTAINS_TOLERANCE))
            return decide_pixels(_COMPILED, self._loop_tables[0], tri, origin, directions, height, width, want_distance, skip, narrow)
        tri = np.asarray(tri, dtype=np.intp)
        o = np.asarray(origin, dtype=np.float64)
        d = tuple(np.asarray(r, dtype=np.float64) for r in directions)
        shown, t, crease_ray, crease_group = self._decide(tri, o, d, want_distance, skip)
        face = np.maximum(shown, 0)
        seen = np.where(shown >= 0, np.take(self._rows.outline, face), -1).reshape(height, width)
        # a pixel is on an outline where one of its 8 neighbours shows another outline value:
        # each of the four directions compared once, marked on both pixels of a pair
        edge = np.zeros((height, width), dtype=bool)
        for here, there in _PAIRS:
            differs = seen[here] != seen[there]
            edge[here] |= differs
            edge[there] |= differs
        pixels = np.flatnonzero(edge.ravel())
        if not len(pixels) and not len(crease_ray):
            return as_asked(shown, t, narrow)
        # candidates: the groups the 3x3 neighbourhood shows (a neighbour beyond the frame's
        # border: the pixel on the border), those across a crease near the hit, and those across
        # a crease near where the ray meets a neighbour's group
        y, x = np.divmod(pixels, width)
        nine = np.clip(y[:, None] + _NINE_DY, 0, height - 1) * width + np.clip(x[:, None] + _NINE_DX, 0, width - 1)
        if self._rows.outline_is_group:
            around = seen.ravel()[nine].astype(np.int64)
        else:
            shows = shown[nine]
            around = np.where(shows >= 0, self.group[np.maximum(shows, 0)], -1)
        # each pixel's distinct groups, ascending (a sort of nine per row, not of them all)
        around.sort(axis=1)
        fresh = around >= 0
        fresh[:, 1:] &= around[:, 1:] != around[:, :-1]
        ray, cand = np.repeat(pixels, fresh.sum(axis=1)), around[fresh]
        if len(crease_ray):
            ray, cand = unique_pairs(np.concatenate([ray, crease_ray]), np.concatenate([cand, crease_group]))
        ray, cand, dist, point = self._reachable(ray, cand, o, d)
        _, extra_at, extra_group = self._near_watched(cand, point)
        if len(extra_at):
            ray, cand = unique_pairs(np.concatenate([ray, ray[extra_at]]), np.concatenate([cand, extra_group]))
            ray, cand, dist, point = self._reachable(ray, cand, o, d)
        ray, face, dist = self._nearest_holding(ray, cand, dist, point, d)
        shown[ray] = face
        if t is not None:
            t[ray] = dist
        return as_asked(shown, t, narrow)

    def _reachable(
        self, ray: np.ndarray, cand: np.ndarray, o: np.ndarray, d: tuple[np.ndarray, ...]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
        """The (ray, candidate group) pairs whose group's plane the ray meets ahead, at a point
        inside the group's ``group_box``, with the distances and points.

        A pair left out could change nothing: a point outside the box is held by none of the
        group's faces and lies near none of its watched edges (``GROUP_BOX_MARGIN``). The box
        test is a few comparisons per pair, where the tests it spares look the point up in the
        cell tables (most of an outline's candidate planes are met outside their faces)."""
        dist = self._distance(cand, o, d, ray)
        ahead = np.flatnonzero(np.isfinite(dist) & (dist > 0))
        point = _points(o, d, ray[ahead], dist[ahead])
        g = cand[ahead]
        box = self._rows.box
        inside = np.ones(len(g), dtype=bool)
        for k in range(3):
            inside &= (point[k] >= np.take(box[k], g)) & (point[k] <= np.take(box[3 + k], g))
        keep = ahead[inside]
        return ray[keep], cand[keep], dist[keep], [p[inside] for p in point]

    def _nearest_holding(
        self, ray: np.ndarray, cand: np.ndarray, dist: np.ndarray, point: list[np.ndarray], d: tuple[np.ndarray, ...]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Of (ray, candidate group) pairs at ``dist`` (finite, ahead; a ray's pairs next to each
        other, as :meth:`_reachable` leaves them): per ray, the nearest candidate whose faces
        hold the ray, as (ray, highest holding face, distance); a tie in distance goes to the
        higher face, a ray no candidate holds is left out.

        The candidates are tested nearest first, a ray's farther ones only where none nearer
        holds it: the answer is the one testing every candidate gives (the order is by the
        exact float64 distances, which are the same on every CPU), without the tests that
        cannot change it (most rays at an outline are held by their nearest candidate)."""
        # a round tests, per ray still open, its candidates at the least distance not yet
        # tested (a minimum per run of one ray's pairs: no sort)
        live = np.arange(len(ray))  # the pairs not yet tested, of rays not yet decided
        found = []
        while len(live):
            lray, ldist = ray[live], dist[live]
            new_ray = np.ones(len(live), dtype=bool)
            new_ray[1:] = lray[1:] != lray[:-1]
            starts = np.flatnonzero(new_ray)
            which = np.cumsum(new_ray) - 1  # each live pair's ray, counted from 0
            nearest = np.minimum.reduceat(ldist, starts)
            tested = ldist == np.take(nearest, which)
            member = live[tested]
            at = self.faces.find(key_of(cand[member], [p[member] for p in point], CELL))
            face = np.full(len(member), -1, dtype=np.int64)
            listed = np.flatnonzero(at >= 0)
            face[listed] = self._highest_holding(at[listed], [p[member[listed]] for p in point], ray[member[listed]], d)
            # per ray, the highest face among its tested pairs (each ray has at least one)
            best = np.maximum.reduceat(face, np.flatnonzero(np.r_[True, which[tested][1:] != which[tested][:-1]]))
            held = best >= 0
            found.append((lray[starts[held]], best[held], nearest[held]))
            live = live[~tested & ~np.take(held, which)]
        if not found:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
        rays, faces, dists = zip(*found)
        return np.concatenate(rays), np.concatenate(faces), np.concatenate(dists)

    # -- the exact tests --------------------------------------------------------------------
    def _side(self, face: np.ndarray, d: tuple[np.ndarray, ...], ray: np.ndarray) -> np.ndarray:
        """Which side of its face each ray meets: 0 against the face's normal, 1 along it."""
        own = self._rows.own
        facing = np.take(own[0], face) * np.take(d[0], ray)
        facing += np.take(own[1], face) * np.take(d[1], ray)
        facing += np.take(own[2], face) * np.take(d[2], ray)
        return (facing >= 0).astype(np.intp)

    def _face_distance(self, face: np.ndarray, o: np.ndarray, d: tuple[np.ndarray, ...], ray: np.ndarray | None = None) -> np.ndarray:
        """:meth:`_distance` to each face's group plane, from per-face rows (the same values);
        ``ray`` ``None``: face i is ray i's."""
        plane = self._rows.plane
        nx, ny, nz = (np.take(plane[k], face) for k in range(3))
        if o.ndim == 1:  # one origin: the plane's offset from it once per face
            across = np.take(plane[3] - (plane[0] * o[0] + plane[1] * o[1] + plane[2] * o[2]), face)
        else:
            ox, oy, oz = (o[k] if ray is None else o[k][ray] for k in range(3))
            across = np.take(plane[3], face) - (nx * ox + ny * oy + nz * oz)
        dx, dy, dz = (d[k] if ray is None else np.take(d[k], ray) for k in range(3))
        along = nx * dx
        along += ny * dy
        along += nz * dz
        return np.divide(across, along, out=np.full(len(face), np.inf), where=along != 0)

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
        watching = self.watching[group]  # only groups with a watched edge are looked up
        some = None if watching.all() else np.flatnonzero(watching)
        at = self.watched.find(key_of(group, point, EDGE_CELL) if some is None else key_of(group[some], [p[some] for p in point], EDGE_CELL))
        listed = np.flatnonzero(at >= 0)
        if some is not None:
            listed = some[listed]
        row, edge = self.watched.explode(at[at >= 0])
        row = listed[row]
        # (the same products and sums as on the (E, 4) and (E, 5) arrays, gathered from rows)
        line, along = self._rows.line, self._rows.along
        x = [p[row] for p in point]
        off = np.take(line[0], edge) * x[0]
        off += np.take(line[1], edge) * x[1]
        off += np.take(line[2], edge) * x[2]
        off -= np.take(line[3], edge)
        pos = np.take(along[0], edge) * x[0]
        pos += np.take(along[1], edge) * x[1]
        pos += np.take(along[2], edge) * x[2]
        close = (np.abs(off) < EDGE_MARGIN) & (pos > np.take(along[3], edge) - EDGE_MARGIN) & (pos < np.take(along[4], edge) + EDGE_MARGIN)
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
        rows = self._rows
        # each coordinate gathered once; each face's numbers from contiguous per-face rows
        # (the same products and sums, in the same order, as on (F, 3) arrays)
        x, y, z = (p[row] for p in point)
        rr = ray[row]
        facing = np.take(rows.own[0], g) * np.take(d[0], rr)
        facing += np.take(rows.own[1], g) * np.take(d[1], rr)
        facing += np.take(rows.own[2], g) * np.take(d[2], rr)
        inside = np.take(rows.open, g) | (facing < 0)
        for e in range(3):
            m = rows.edges[e]
            signed = np.take(m[0], g) * x
            signed += np.take(m[1], g) * y
            signed += np.take(m[2], g) * z
            signed -= np.take(m[3], g)
            inside &= signed >= -CONTAINS_TOLERANCE
        # a key's faces are listed highest first: a row's first face inside is its highest
        hit = np.flatnonzero(inside)
        first = np.ones(len(hit), dtype=bool)
        first[1:] = row[hit[1:]] != row[hit[:-1]]
        best = np.full(len(at), -1, dtype=np.int64)
        best[row[hit[first]]] = g[hit[first]]
        return best


# -- helpers ----------------------------------------------------------------------------------
def _points(o: np.ndarray, d: tuple[np.ndarray, ...], ray: np.ndarray, dist: np.ndarray) -> list[np.ndarray]:
    """The points ``o + d * dist`` of the given rays, one array per coordinate."""
    return [(o[k] if o.ndim == 1 else o[k][ray]) + d[k][ray] * dist for k in range(3)]

"""The faces a camera's pixels show: the shortcuts of :meth:`VisibleFaces.decide_image` (the
skip of hits in no watched edge's cell, a candidate group's box, candidates tested nearest
first) change no pixel and no distance against testing every candidate everywhere, and the box
they rest on holds every point the exact tests could accept."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate.face_groups import CONTAINS_TOLERANCE, cross, dot3, group_boxes, inward_edges, unit
from povagent.generate.visible_face import EDGE_MARGIN, VisibleFaces, _points


def every_candidate_reachable(self, ray, cand, o, d):
    """The pairs ahead, without the box test (the reference)."""
    dist = self._distance(cand, o, d, ray)
    ahead = np.flatnonzero(np.isfinite(dist) & (dist > 0))
    return ray[ahead], cand[ahead], dist[ahead], _points(o, d, ray[ahead], dist[ahead])


def every_candidate_tested(self, ray, cand, dist, point, d):
    """Every candidate tested at once, the nearest holding one kept per ray (a tie in
    distance: the higher face): the decision as it reads, with no test left out."""
    from povagent.generate.cell_table import key_of
    from povagent.generate.visible_face import CELL

    at = self.faces.find(key_of(cand, point, CELL))
    face = np.full(len(ray), -1, dtype=np.int64)
    listed = np.flatnonzero(at >= 0)
    face[listed] = self._highest_holding(at[listed], [p[listed] for p in point], ray[listed], d)
    held = face >= 0
    ray, dist, face = ray[held], dist[held], face[held]
    order = np.lexsort((-face, dist, ray))
    ray, dist, face = ray[order], dist[order], face[order]
    first = np.ones(len(ray), dtype=bool)
    first[1:] = ray[1:] != ray[:-1]
    return ray[first], face[first], dist[first]


@pytest.fixture(scope="module", params=[(0, 0), (7, 2)], ids=["house-0-0", "house-7-2"])
def views(request):
    """A generated house's renderer and the embree hits of four of its exploration views."""
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house

    built = build_house(*request.param, shadows=False)
    renderer = built.renderer
    hits = []
    for camera in plan_tour(built.house, renderer, 4):
        d = renderer._directions(camera)
        origin = np.asarray(camera.position, dtype=np.float32)
        out = renderer._scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=1)
        hits.append((out["primID"].astype(np.intp), origin, d, camera.height, camera.width))
    return renderer, hits


@pytest.mark.parametrize("objects_only", [False, True], ids=["faces", "objects"])
def test_the_shortcuts_change_no_pixel_against_testing_every_candidate(views, objects_only, monkeypatch):
    renderer, hits = views
    faces = renderer._objects if objects_only else renderer._visible
    fast = [faces.decide_image(*h, want_distance=not objects_only, skip=True) for h in hits]
    monkeypatch.setattr(VisibleFaces, "_reachable", every_candidate_reachable)
    monkeypatch.setattr(VisibleFaces, "_nearest_holding", every_candidate_tested)
    for (tri, *args), (shown, t) in zip(hits, fast):
        exact = faces.decide_image(tri, *args, want_distance=not objects_only)
        assert np.array_equal(shown, exact[0])
        if not objects_only:
            assert np.array_equal(t, exact[1])
        # the views do exercise the decision: pixels whose face differs from embree's
        assert (shown != tri).any()


def holds(own, edges, offsets, point):
    """The containment test of ``VisibleFaces._highest_holding`` for one face (either side)."""
    return all(float(edges[k] @ point) - offsets[k] >= -CONTAINS_TOLERANCE for k in range(3)) and np.any(own)


def test_a_group_box_holds_every_point_its_faces_hold_even_at_a_sliver_s_sharp_corner():
    rng = np.random.default_rng(3)
    # slivers (a corner down to a thousandth of a radian) and ordinary triangles, in tilted planes
    corners = []
    for k in range(40):
        a = rng.random(3) * 4
        u, v = np.linalg.qr(rng.normal(size=(3, 2)))[0].T
        angle = 10.0 ** rng.uniform(-3, -1) if k % 2 else rng.uniform(0.3, 2.5)
        b = a + u * rng.uniform(0.1, 2)
        corners.append((a, b, a + (np.cos(angle) * u + np.sin(angle) * v) * rng.uniform(0.1, 2)))
    a, b, c = (np.array([t[i] for t in corners]) for i in range(3))
    own = unit(cross(b - a, c - a))
    group = np.arange(len(a))
    box = group_boxes((a, b, c), own, group, own, dot3(own, a), EDGE_MARGIN)
    edges, offsets = inward_edges(own, a, b, c)
    checked = 0
    for f in range(len(a)):
        # points around each corner and edge, on the face's plane, out to a few times the reach
        for start in (a[f], b[f], c[f]):
            for r in (1e-5, 1e-4, 1e-3, 1e-2):
                for direction in unit(rng.normal(size=(60, 3))):
                    step = direction - own[f] * float(direction @ own[f])
                    point = start + step * r
                    if holds(own[f], edges[f], offsets[f], point):
                        checked += 1
                        assert (box[f, :3] <= point).all() and (point <= box[f, 3:]).all()
        # and points near its edges, as far as the near-edge test reaches
        for p, q in ((a[f], b[f]), (b[f], c[f]), (c[f], a[f])):
            for along in np.linspace(-EDGE_MARGIN / float(np.linalg.norm(q - p)), 1 + EDGE_MARGIN / float(np.linalg.norm(q - p)), 9):
                for direction in unit(rng.normal(size=(8, 3))):
                    point = p + (q - p) * along + (direction - own[f] * float(direction @ own[f])) * EDGE_MARGIN
                    assert (box[f, :3] <= point).all() and (point <= box[f, 3:]).all()
    assert checked > 1000


def test_a_group_box_hugs_an_axis_aligned_square_within_a_millimetre():
    a = np.array([[0.0, 0, 0], [1.0, 0, 1]])
    b = np.array([[1.0, 0, 0], [0.0, 0, 1]])
    c = np.array([[1.0, 0, 1], [0.0, 0, 0]])
    own = unit(cross(b - a, c - a))
    box = group_boxes((a, b, c), own, np.array([0, 0]), own[:1], dot3(own, a)[:1], EDGE_MARGIN)
    assert np.allclose(box[0], [0, 0, 0, 1, 0, 1], atol=1e-3)
    assert (box[0, :3] < [0, 0, 0]).all() and (box[0, 3:] > [1, 0, 1]).all()


def test_a_degenerate_face_s_group_box_is_the_whole_space():
    a, b = np.array([[0.0, 0, 0]]), np.array([[1.0, 0, 0]])
    own = unit(cross(b - a, b - a))
    box = group_boxes((a, b, b), own, np.array([0]), np.array([[0.0, 1, 0]]), np.array([0.0]), EDGE_MARGIN)
    assert np.isinf(box).all()

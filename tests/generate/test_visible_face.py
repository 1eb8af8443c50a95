"""The faces a camera's pixels show: the shortcuts of :meth:`VisibleFaces.decide_image` (the
skip of hits in no watched edge's cell, a candidate group's box, candidates tested nearest
first) change no pixel and no distance against testing every candidate everywhere, and the box
they rest on holds every point the exact tests could accept; the compiled loop
(``visible_face.c``) decides every pixel and distance as numpy's passes do."""

from __future__ import annotations

import shutil
import sys

import numpy as np
import pytest

from povagent.generate import visible_face
from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.face_groups import CONTAINS_TOLERANCE, cross, dot3, group_boxes, inward_edges, unit
from povagent.generate.visible_face import EDGE_MARGIN, VisibleFaces, _points
from povagent.geometry.camera import Camera
from tests.generate.compiled_paths import OTHER_BUILDS, each_path, other_build

path = pytest.fixture(params=["compiled", "numpy"])(each_path(visible_face))


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
    """A generated house's renderer and the embree hits of four of its exploration views and of
    a camera outside it (rays that hit nothing beside rays that hit its wall)."""
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house

    built = build_house(*request.param, shadows=False)
    renderer = built.renderer
    rooms = built.house.plan.rooms
    outside = Camera.from_pose((min(r.rect.center[0] for r in rooms) - 6.0, 1.4, rooms[0].rect.center[1]), 90.0, -30.0, 100.0)
    hits = []
    for camera in [*plan_tour(built.house, renderer, 4), outside]:
        d = renderer._directions(camera)
        origin = np.asarray(camera.position, dtype=np.float32)
        out = renderer._scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=1)
        hits.append((out["primID"].astype(np.intp), origin, d, camera.height, camera.width))
    assert (hits[-1][0] < 0).any() and (hits[-1][0] >= 0).any()
    return renderer, hits


@pytest.fixture(scope="module")
def decisions(views):
    """``decisions(objects_only, loop, want_distance, skip)``: ``decide_image``'s answers for each
    of a house's views on ``loop`` (the compiled loop, or ``None``: numpy's passes). Made on first
    use and kept for the module's house: several tests compare the same answers (the shortcuts'
    with the reference, each path's with the other's, the wide with the narrow, the installed
    loop's with another build's), and numpy's cost more than the comparisons."""
    renderer, hits = views
    made: dict[tuple, list[tuple[np.ndarray, np.ndarray | None]]] = {}

    def decide(objects_only: bool, loop, want_distance: bool, skip: bool) -> list[tuple[np.ndarray, np.ndarray | None]]:
        key = (objects_only, loop, want_distance, skip)
        if key not in made:
            faces = renderer._objects if objects_only else renderer._visible
            with pytest.MonkeyPatch.context() as patch:
                patch.setattr(visible_face, "_COMPILED", loop)
                made[key] = [faces.decide_image(*h, want_distance=want_distance, skip=skip) for h in hits]
        return made[key]

    return decide


@pytest.fixture(scope="module")
def every_candidate(views):
    """``every_candidate(objects_only)``: the reference decisions of a house's views (numpy's
    passes, every candidate tested). Made on first use and kept for the module's house: both
    paths' cases compare with the same reference, and it costs more than either."""
    renderer, hits = views
    made: dict[bool, list[tuple[np.ndarray, np.ndarray | None]]] = {}

    def reference(objects_only: bool) -> list[tuple[np.ndarray, np.ndarray | None]]:
        if objects_only not in made:
            faces = renderer._objects if objects_only else renderer._visible
            with pytest.MonkeyPatch.context() as patch:
                patch.setattr(visible_face, "_COMPILED", None)
                patch.setattr(VisibleFaces, "_reachable", every_candidate_reachable)
                patch.setattr(VisibleFaces, "_nearest_holding", every_candidate_tested)
                made[objects_only] = [faces.decide_image(tri, *args, want_distance=not objects_only) for tri, *args in hits]
        return made[objects_only]

    return reference


@pytest.mark.parametrize("objects_only", [False, True], ids=["faces", "objects"])
def test_the_shortcuts_change_no_pixel_against_testing_every_candidate(views, decisions, every_candidate, objects_only, path):
    _, hits = views
    fast = decisions(objects_only, visible_face._COMPILED, not objects_only, True)  # (the path's loop, or None)
    # the reference: numpy's passes, every candidate tested
    for (shown, t), exact in zip(fast, every_candidate(objects_only), strict=True):
        assert np.array_equal(shown, exact[0])
        if not objects_only:
            assert np.array_equal(t, exact[1])
    # the views do exercise the decision: pixels whose face differs from embree's
    assert all((shown != tri).any() for (tri, *_), (shown, _) in zip(hits[:-1], fast))


def compiled_or_skip():
    loop = compiled_loop(visible_face._LOOP)
    if loop is None:
        pytest.skip("the compiled loop is not built here (or POVAGENT_PURE_NUMPY is set)")
    return loop


def both_paths(faces, args, monkeypatch, **flags):
    """``decide_image`` on the compiled loop and on numpy's passes."""
    loop = compiled_or_skip()
    decided = []
    for module in (loop, None):
        monkeypatch.setattr(visible_face, "_COMPILED", module)
        decided.append(faces.decide_image(*args, **flags))
    return decided


def assert_same(compiled, numpy_s, want_distance):
    assert compiled[0].dtype == numpy_s[0].dtype and np.array_equal(compiled[0], numpy_s[0])
    if want_distance:
        assert compiled[1].dtype == numpy_s[1].dtype and np.array_equal(compiled[1], numpy_s[1])  # inf where nothing is hit
    else:
        assert compiled[1] is None and numpy_s[1] is None


@pytest.mark.parametrize("want_distance", [True, False], ids=["distances", "no-distances"])
@pytest.mark.parametrize("skip", [True, False], ids=["skip", "no-skip"])
@pytest.mark.parametrize("objects_only", [False, True], ids=["faces", "objects"])
def test_the_compiled_loop_decides_every_pixel_and_distance_as_numpy(decisions, objects_only, skip, want_distance):
    loop = compiled_or_skip()
    compiled, numpy_s = (decisions(objects_only, module, want_distance, skip) for module in (loop, None))
    for one, other in zip(compiled, numpy_s, strict=True):
        assert_same(one, other, want_distance)


@pytest.mark.parametrize("objects_only", [False, True], ids=["faces", "objects"])
def test_the_narrow_answer_is_the_wide_one_rounded_on_both_paths(views, decisions, objects_only, monkeypatch):
    """The renderer's call: embree's int32 triangles read as they are, int32 faces and float32
    distances back (the loop writes them so, numpy's path casts its answer): the wide answer's
    values, the same on both paths."""
    renderer, hits = views
    faces = renderer._objects if objects_only else renderer._visible
    want = not objects_only
    wide_compiled, wide_numpy = (decisions(objects_only, module, want, True) for module in (compiled_or_skip(), None))
    for (tri, *rest), *wide in zip(hits, wide_compiled, wide_numpy, strict=True):
        narrow = both_paths(faces, (tri.astype(np.int32), *rest), monkeypatch, want_distance=want, skip=True, narrow=True)
        for (shown, t), (shown32, t32) in zip(wide, narrow):
            assert shown32.dtype == np.int32 and np.array_equal(shown32, shown)
            if want:
                assert t32.dtype == np.float32 and np.array_equal(t32, t.astype(np.float32))  # inf where nothing is hit
        assert_same(*narrow, want)


def test_a_no_hit_below_int32_keeps_its_value(views, monkeypatch):
    """The loop keeps the faces as int32: an int64 "no hit" below that range is answered by
    numpy's path (as it is), and the loop called with it refuses it rather than change it."""
    from povagent.generate.visible_face_loop import decide_pixels

    renderer, hits = views
    tri, *rest = hits[-1]  # the camera outside: rays that hit nothing beside rays that hit the wall
    odd = np.where(tri < 0, -(2**40), tri)
    compiled, numpy_s = both_paths(renderer._visible, (odd, *rest), monkeypatch, skip=True)
    assert_same(compiled, numpy_s, want_distance=True)
    assert (compiled[0] == -(2**40)).sum() == (tri < 0).sum() > 0
    monkeypatch.setattr(visible_face, "_COMPILED", compiled_or_skip())
    renderer._visible.decide_image(tri, *rest, skip=True)  # (the loop's tables laid out)
    with pytest.raises(ValueError, match="below int32"):
        decide_pixels(compiled_or_skip(), renderer._visible._loop_tables[0], odd, *rest, True, True)


@pytest.mark.skipif((shutil.which("cc") is None and shutil.which("gcc") is None) or sys.platform == "win32", reason="no C compiler to build the generic loop")
@OTHER_BUILDS
def test_the_loop_built_for_another_cpu_decides_as_the_installed_one(views, decisions, tmp_path, monkeypatch, extra):
    """The installed loop takes four pixels at a time with AVX2 (the first pass) and AVX (the
    near cells) where the CPU has them, and a row's outline with AVX-512 or AVX2; built without
    those paths (SSE2 and scalar), or as the AVX2 clone, it decides every pixel and distance
    alike."""
    renderer, hits = views
    installed, generic = compiled_or_skip(), other_build(tmp_path, "visible_face", extra)
    monkeypatch.setattr(visible_face, "_COMPILED", generic)
    # (the AVX2 clone's code differs from the generic build's in the row outline only: two
    # views inside and the one from outside show it)
    views_compared = slice(None, None, 2) if extra else slice(None)
    for h, by_installed in zip(hits[views_compared], decisions(False, installed, True, True)[views_compared], strict=True):
        assert_same(by_installed, renderer._visible.decide_image(*h, want_distance=True, skip=True), want_distance=True)


def box(lo, hi):
    """An axis-aligned box's 8 corners and 12 triangles, wound outward."""
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    tris = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    centre = corners.mean(axis=0)
    v = corners[tris]
    inward = (np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]) * (v.mean(axis=1) - centre)).sum(axis=1) < 0
    tris[inward] = tris[inward][:, ::-1]
    return corners, tris


def quad(a, b, c, d):
    """An open quad's corners and its two triangles."""
    return np.array([a, b, c, d], dtype=float), np.array([[0, 1, 2], [0, 2, 3]])


def microscope(at, seen_from) -> Camera:
    """A camera at ``seen_from`` looking at ``at`` with a field of view of a 500th of a degree."""
    v = np.subtract(at, seen_from) / np.linalg.norm(np.subtract(at, seen_from))
    return Camera.from_pose(seen_from, float(np.degrees(np.arctan2(v[0], v[2]))), float(np.degrees(np.arcsin(-v[1]))), 0.002, 64, 48)


@pytest.fixture(scope="module")
def made_up_scene():
    """A small mesh of the hard cases: a rug on a floor and a mattress flush with its frame's top
    (coplanar faces of other looks overlapping), two boxes side by side (creases, a shared plane
    met from either side), a wall of two halves; seen by cameras grazing the frame's top, from
    above and looking past everything into nothing, and through a microscope (about two
    micrometres a pixel) at a crease, the mattress's edge, the rug's edge and the wall's seam,
    where the near-edge tests decide. Its faces, and embree's hits of each camera."""
    from povagent.generate.renderer import _embree_scene

    parts = [  # (corners and triangles, look, closed)
        (quad((-3, 0, -3), (3, 0, -3), (3, 0, 3), (-3, 0, 3)), 0, False),
        (quad((-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)), 1, False),
        (box((0.5, 0, 0.5), (1.5, 0.8, 1.5)), 2, True),
        (box((1.5, 0, 0.5), (2.2, 0.5, 1.5)), 3, True),
        (box((-2, 0, -2), (-0.5, 0.4, -0.5)), 4, True),
        (box((-1.9, 0.3, -1.9), (-0.6, 0.4, -0.6)), 5, True),
        (quad((-3, 0, -3), (0, 0, -3), (0, 2.5, -3), (-3, 2.5, -3)), 6, False),
        (quad((0, 0, -3), (3, 0, -3), (3, 2.5, -3), (0, 2.5, -3)), 7, False),
    ]
    vertices, faces, looks, closed = [], [], [], []
    for (corners, tris), look, solid in parts:
        faces.append(tris + sum(len(v) for v in vertices))
        vertices.append(corners)
        looks += [look] * len(tris)
        closed += [solid] * len(tris)
    v, f = np.concatenate(vertices).astype(np.float32), np.concatenate(faces)
    looks_, closed_ = np.array(looks), np.array(closed)
    scene = _embree_scene(v, f)
    cameras = [
        Camera.from_pose((0.3, 0.4, 2.5), 200.0, 0.0, 90.0, 96, 80),  # level with the frame's top
        Camera.from_pose((0.0, 2.0, 3.0), 180.0, 35.0, 90.0, 96, 80),
        Camera.from_pose((0.0, 1.0, 2.9), 170.0, -40.0, 100.0, 96, 80),
        *(
            microscope(at, seen_from)
            for at, seen_from in (
                ((1.0, 0.8, 1.5), (1.0, 1.6, 3.0)),
                ((-1.9, 0.4, -1.2), (-1.1, 1.6, -0.2)),
                ((1.0, 0.0, 0.0), (0.7, 1.8, -1.5)),
                ((0.0, 1.2, -3.0), (0.5, 1.4, 0.0)),
                ((0.0, 0.0, -3.0), (0.5, 1.4, 0.0)),  # where the seam's end meets the floor
                ((1.5, 0.8, 1.5), (1.0, 1.6, 3.0)),  # a box's corner
            )
        ),
    ]
    hits = []
    for camera in cameras:
        u, w = np.meshgrid(np.arange(camera.width) + 0.5, np.arange(camera.height) + 0.5)
        d = np.ascontiguousarray(camera.ray(np.stack([u.ravel(), w.ravel()], axis=1)).T, dtype=np.float32)
        origin = np.asarray(camera.position, dtype=np.float32)
        out = scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=1)
        hits.append((out["primID"].astype(np.intp), origin, d, camera.height, camera.width))
    built = [VisibleFaces.build(v, f, looks_, closed_), VisibleFaces.build(v, f, looks_, closed_, by_look=True)]
    return built, hits


@pytest.mark.parametrize("by_look", [False, True], ids=["faces", "looks"])
def test_the_compiled_loop_decides_the_hard_cases_as_numpy(made_up_scene, by_look, monkeypatch):
    built, hits = made_up_scene
    faces = built[by_look]
    rng = np.random.default_rng(11)
    changed = 0
    for tri, *rest in hits:
        # embree's answer and other CPUs': some hits reported on another face (any face), and
        # the faces of the pixels 12 rows or columns over (near an edge, the face beyond it: in
        # the microscope's views, where only the near-edge tests decide them)
        other = tri.copy()
        pick = rng.random(len(tri)) < 0.1
        other[pick & (tri >= 0)] = rng.integers(0, len(faces.group), int((pick & (tri >= 0)).sum()))
        height, width = rest[2], rest[3]
        shifted = [np.where(tri >= 0, np.roll(tri.reshape(height, width), shift, axis=axis).ravel(), tri) for shift, axis in ((-12, 0), (12, 1))]
        for candidate in (tri, other, *shifted):
            for want_distance in (True, False):
                for skip in (True, False):
                    compiled, numpy_s = both_paths(faces, (candidate, *rest), monkeypatch, want_distance=want_distance, skip=skip)
                    assert_same(compiled, numpy_s, want_distance)
            changed += int((compiled[0] != candidate).sum())
    # the scene does exercise the decision, and rays that hit nothing
    assert changed > 100
    assert any((tri < 0).any() for tri, *_ in hits)
    assert faces.overlapped.any() and (faces.edge_across >= 0).any()


def test_directions_other_than_float32_take_numpys_path_to_the_same_pixels(views, path):
    renderer, hits = views
    tri, origin, d, height, width = hits[0]
    faces = renderer._visible
    plain = faces.decide_image(tri, origin, d, height, width, skip=True)
    wide = faces.decide_image(tri, origin, d.astype(np.float64), height, width, skip=True)
    assert np.array_equal(plain[0], wide[0]) and np.array_equal(plain[1], wide[1])


def test_a_triangle_beyond_the_mesh_is_refused(views, path):
    renderer, hits = views
    tri, *rest = hits[0]
    beyond = tri.copy()
    beyond[7] = renderer._visible.group.size
    with pytest.raises(IndexError):
        renderer._visible.decide_image(beyond, *rest, skip=True)


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


@pytest.mark.filterwarnings("ignore:invalid value encountered in cast:RuntimeWarning")  # (numpy's path, casting the NaN cell)
def test_a_direction_that_is_not_finite_is_refused_where_hits_are_looked_up_in_the_near_cells(views, path):
    renderer, hits = views
    tri, origin, d, height, width = hits[0]
    broken = d.copy()
    broken[:, 100] = np.nan
    with pytest.raises(IndexError):
        renderer._visible.decide_image(tri, origin, broken, height, width, skip=True)


def test_a_pickled_copy_lays_the_loops_tables_out_again_and_decides_alike(views, path):
    import pickle

    renderer, hits = views
    faces = renderer._visible
    before = faces.decide_image(*hits[0], skip=True)
    copy = pickle.loads(pickle.dumps(faces))
    assert copy._loop_tables == []
    after = copy.decide_image(*hits[0], skip=True)
    assert np.array_equal(before[0], after[0]) and np.array_equal(before[1], after[1])

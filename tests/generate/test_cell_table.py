"""The cell tables behind the visible-face decisions: the dense mask of cells an edge may be
near, and that skipping the cells it leaves out changes no decision."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate.cell_table import CellMask, cell

SIZE = 0.0625


def test_every_point_in_a_boxs_cells_is_covered():
    rng = np.random.default_rng(0)
    low = rng.integers(-40, 40, size=(30, 3))
    high = low + rng.integers(0, 6, size=(30, 3))
    mask = CellMask.build(low, high, SIZE)
    assert mask is not None
    # points anywhere in each box, right up to its faces
    box = rng.integers(0, 30, size=5000)
    point = (low[box] + rng.random((5000, 3)) * (high[box] - low[box] + 1)) * SIZE
    assert mask.covers(point[:, 0], point[:, 1], point[:, 2]).all()


def test_a_cell_is_covered_exactly_when_a_table_key_would_list_it():
    """No margin: the cells next to a box are not covered (the mask answers as the table does)."""
    low, high = np.array([[0, 0, 0]]), np.array([[2, 0, 0]])
    mask = CellMask.build(low, high, SIZE)
    assert mask is not None
    x = (np.arange(-3, 6) + 0.5) * SIZE
    covered = mask.covers(x, np.full(9, SIZE / 2), np.full(9, SIZE / 2))
    assert covered.tolist() == [c in (0, 1, 2) for c in range(-3, 6)]
    # the cell boundaries are the ones ``cell`` (hence a key) puts a point in
    edges = np.array([0.0, -1e-12, 3 * SIZE, 3 * SIZE - 1e-12])
    assert mask.covers(edges, np.full(4, SIZE / 2), np.full(4, SIZE / 2)).tolist() == [True, False, False, True]


def test_a_point_two_cells_away_from_every_box_is_not_covered():
    low = np.array([[0, 0, 0], [10, 0, 0]])
    high = np.array([[1, 1, 1], [12, 1, 1]])
    mask = CellMask.build(low, high, SIZE)
    assert mask is not None
    inside = [(c * SIZE + SIZE / 2,) for c in (0, 1, 11)]
    far = [(c * SIZE + SIZE / 2,) for c in (5, 6, 7, -5, 20)]
    pad = np.zeros(1) + SIZE / 2
    assert mask.covers(np.array(inside[0] + inside[1] + inside[2]), np.repeat(pad, 3), np.repeat(pad, 3)).all()
    assert not mask.covers(np.array(sum(far, ())), np.repeat(pad, 5), np.repeat(pad, 5)).any()


def test_a_grid_too_large_is_not_built():
    assert CellMask.build(np.array([[0, 0, 0]]), np.array([[1 << 10, 1 << 10, 1 << 10]]), SIZE) is None
    assert CellMask.build(np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3), dtype=np.int64), SIZE) is None
    # nor one reaching the cells where a key is clipped (a point beyond would share its key)
    assert CellMask.build(np.array([[1023, 0, 0]]), np.array([[1023, 1, 1]]), SIZE) is None


def test_cells_match_the_tables_cells():
    x = np.array([-0.0625, -0.0001, 0.0, 0.0624, 0.0625, 1.0])
    assert cell(x, SIZE).tolist() == [-1, -1, 0, 0, 1, 16]


@pytest.fixture(scope="module")
def house_views():
    """A generated house's renderer and embree's hits of three of its exploration views: built
    once for both of the test's cases (a build and its ray casts cost more than the checks)."""
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house

    built = build_house(0, 0, shadows=False)
    renderer = built.renderer
    hits = []
    for camera in plan_tour(built.house, renderer, 3):
        d = renderer._directions(camera)
        origin = np.asarray(camera.position, dtype=np.float32)
        out = renderer._scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=1)
        hits.append((out["primID"].astype(np.intp), origin, d, camera.height, camera.width))
    return renderer, hits


@pytest.mark.parametrize("objects_only", [False, True])
def test_skipping_hits_in_no_edges_cell_changes_no_pixel(house_views, objects_only):
    """The same faces and distances with and without the skip, on a generated house's views."""
    renderer, hits = house_views
    faces = renderer._objects if objects_only else renderer._visible
    for args in hits:
        plain = faces.decide_image(*args, want_distance=not objects_only)
        skipping = faces.decide_image(*args, want_distance=not objects_only, skip=True)
        assert np.array_equal(plain[0], skipping[0])
        if not objects_only:
            assert np.array_equal(plain[1], skipping[1])

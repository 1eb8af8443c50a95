"""The geodesic shortest path on a floor grid (SPL's ``l``), checked on hand-made floors, and
SPL itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.active.geodesic import FloorGrid, path_length, spl

#: A floor of 5 x 5 cells, 0.5 m apart; a wall (column 2, rows 0-3) leaves a gap at row 4.
WALLED = np.ones((5, 5), dtype=bool)
WALLED[2, 0:4] = False


def grid(free: np.ndarray, clear=None) -> FloorGrid:
    return FloorGrid(free, (0.0, 0.0), 0.5, clear)


def at(*cells: tuple[int, int]):
    return set(cells).__contains__


def test_a_straight_run_of_open_floor_is_its_length():
    path = grid(np.ones((5, 1), dtype=bool)).shortest((0.0, 0.0), at((4, 0)))
    assert path is not None and path.length == pytest.approx(2.0)
    assert path.points[-1] == (2.0, 0.0)


def test_a_diagonal_step_costs_its_length_in_the_open():
    path = grid(np.ones((3, 3), dtype=bool)).shortest((0.0, 0.0), at((2, 2)))
    assert path is not None and path.length == pytest.approx(2 * 0.5 * math.sqrt(2))


def test_the_path_goes_round_a_wall_through_its_gap():
    path = grid(WALLED).shortest((0.0, 0.0), at((4, 0)))
    # (0,0) -> (1,4): 3 straight steps and a diagonal; into and out of the gap straight (a
    # diagonal would cut the wall's end): (1,4) -> (2,4) -> (3,4); (3,4) -> (4,0): 3 + 1 again
    assert path is not None
    assert path.length == pytest.approx(8 * 0.5 + 2 * 0.5 * math.sqrt(2))
    assert (1.0, 2.0) in path.points  # the gap, column 2 of row 4
    assert path_length(path.points) == pytest.approx(path.length)


def test_a_diagonal_never_cuts_a_corner():
    free = np.array([[True, False], [True, True]])  # (0,1) blocked: (0,0) -> (1,1) must go round
    path = grid(free).shortest((0.0, 0.0), at((1, 1)))
    assert path is not None and path.length == pytest.approx(1.0)


def test_no_reachable_goal_gives_no_path():
    free = np.array([[True, False, True]])
    assert grid(free).shortest((0.0, 0.0), at((0, 2))) is None


def test_the_nearest_goal_cell_ends_the_path():
    path = grid(np.ones((7, 1), dtype=bool)).shortest((1.0, 0.0), at((0, 0), (6, 0)))
    assert path is not None and path.points[-1] == (0.0, 0.0) and path.length == pytest.approx(1.0)


def test_a_start_off_the_grid_walks_to_the_nearest_free_cell_first():
    path = grid(np.ones((3, 1), dtype=bool)).shortest((0.0, 0.3), at((2, 0)))
    assert path is not None and path.points[:2] == ((0.0, 0.3), (0.0, 0.0))
    assert path.length == pytest.approx(0.3 + 1.0)


def test_a_step_the_walk_check_refuses_is_no_edge():
    def no_crossing_x_half(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        return ~((np.minimum(starts[:, 0], ends[:, 0]) < 0.75) & (np.maximum(starts[:, 0], ends[:, 0]) > 0.75))

    assert grid(np.ones((3, 1), dtype=bool), no_crossing_x_half).shortest((0.0, 0.0), at((2, 0))) is None


def test_grid_of_cell_centres_rebuilds_the_lattice():
    points = np.array([(1.0, -2.0), (1.25, -2.0), (1.5, -2.0), (1.5, -1.75)])
    floor = FloorGrid.of_cells(points, 0.25)
    path = floor.shortest((1.0, -2.0), lambda c: floor.centre(c) == (1.5, -1.75))
    assert path is not None and path.length == pytest.approx(0.75)


def test_spl_is_the_shortest_over_the_longer_of_walked_and_shortest():
    assert spl(True, 4.0, 4.0) == 1.0
    assert spl(True, 4.0, 8.0) == 0.5
    assert spl(True, 4.0, 3.0) == 1.0  # a walk shorter than the grid's path is not rewarded above 1
    assert spl(False, 4.0, 4.0) == 0.0
    assert spl(True, 0.0, 0.0) == 1.0

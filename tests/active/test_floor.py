"""Moves stop at walls and furniture (0.25 m body) and never leave the reachable floor."""

from __future__ import annotations

import numpy as np

from povagent.active.floor import BODY_RADIUS, MAX_MOVE
from povagent.generate.exploration import reachable_grid


def test_a_long_move_stops_at_a_wall_and_says_so(house0, floor0):
    x, z = reachable_grid(house0.built.house).points[0]
    moved = floor0.move(float(x), float(z), 50.0, 0.0)
    assert moved.blocked and moved.travelled < MAX_MOVE
    assert floor0._on_floor(moved.x, moved.z)


def test_a_short_move_in_open_floor_goes_all_the_way(house0, floor0):
    points = reachable_grid(house0.built.house).points
    free = [floor0.move(float(x), float(z), 0.1, 0.0) for x, z in points]
    assert any(not m.blocked and abs(m.travelled - 0.1) < 1e-9 for m in free)


def test_the_body_never_ends_inside_a_blocker_it_was_not_touching(house0, floor0):
    for x, z in reachable_grid(house0.built.house).points[:40]:
        start = floor0._touching(float(x), float(z))
        moved = floor0.move(float(x), float(z), 0.0, 3.0)
        assert not (floor0._touching(moved.x, moved.z) & ~start).any()
    assert BODY_RADIUS == 0.25


def test_a_step_the_clear_check_passes_is_walked_whole_by_a_move(house0, floor0):
    points = reachable_grid(house0.built.house).points.astype(float)
    cells = {(round(x, 4), round(z, 4)) for x, z in points}
    pairs = [((x, z), (x + dx, z + dz)) for x, z in points for dx in (-0.25, 0.0, 0.25) for dz in (-0.25, 0.0, 0.25)
             if (dx or dz) and (round(x + dx, 4), round(z + dz, 4)) in cells]  # fmt: skip
    passes = floor0.clear(np.array([a for a, _ in pairs]), np.array([b for _, b in pairs]))
    assert passes.any() and not passes.all()  # furniture stops some steps between reachable cells
    for ((x, z), (ex, ez)), ok in zip(pairs, passes):
        if ok:
            assert not floor0.move(x, z, ex - x, ez - z).blocked

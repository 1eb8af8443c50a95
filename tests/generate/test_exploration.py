"""The exploration tour: reachable grid positions, every room, the paper's camera."""

from __future__ import annotations

import numpy as np

from povagent.generate.exploration import allocate, plan_tour, reachable_grid


def test_reachable_positions_lie_on_the_quarter_metre_grid(tiny_dataset):
    grid = reachable_grid(tiny_dataset.built.house)
    assert len(grid.points) > 50
    assert np.allclose(grid.points / 0.25, np.round(grid.points / 0.25))


def test_reachable_positions_keep_the_robot_off_furniture(tiny_dataset):
    house = tiny_dataset.built.house
    grid = reachable_grid(house)
    for o in house.objects:
        if o.support == "floor":
            r = o.rect
            inside = (grid.points[:, 0] > r.x0) & (grid.points[:, 0] < r.x1) & (grid.points[:, 1] > r.z0) & (grid.points[:, 1] < r.z1)
            assert not inside.any(), o.object_id


def test_the_tour_starts_in_the_entrance_room_and_visits_every_room(tiny_dataset):
    house, renderer = tiny_dataset.built.house, tiny_dataset.built.renderer
    frames = len(house.plan.rooms) + 2
    cams = plan_tour(house, renderer, frames)
    rooms = [house.plan.room_at(c.position[0], c.position[2]).room_id for c in cams]
    assert len(cams) == frames
    assert rooms[0] == house.plan.entrance.rooms[0]
    assert set(rooms) == {r.room_id for r in house.plan.rooms}


def test_frames_are_shared_by_reachable_floor_and_never_exceed_the_budget():
    # one frame each, then the other 27 by largest remainder of 27 * share
    assert allocate([100, 50, 10], 30) == [18, 9, 3]
    assert sum(allocate([7, 3, 1, 1], 30)) == 12  # a room cannot take more frames than it has cells
    assert allocate([10, 10], 0) == [0, 0]

"""The navigate task's success on a generated house: within 1.0 m of the target on the floor and
the target in view (in the image, in front, not occluded); the goal cells of the shortest path
are the ones that rule accepts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.active.navigation import ARRIVAL_RADIUS, arrived, floor_distance, house_floor, in_view, line_of_sight
from povagent.active.pose import ROBOT_CAMERA_HEIGHT
from povagent.generate.exploration import reachable_grid
from povagent.geometry.camera import Camera

pytestmark = pytest.mark.timeout(120)


def facing(x: float, z: float, target) -> Camera:
    """A robot camera at (x, z) turned and tilted to look straight at the target."""
    dx, dz = target[0] - x, target[2] - z
    yaw = math.degrees(math.atan2(dx, dz)) % 360.0
    horizon = math.degrees(math.atan2(ROBOT_CAMERA_HEIGHT - target[1], math.hypot(dx, dz)))
    return Camera((x, ROBOT_CAMERA_HEIGHT, z), yaw, horizon)


@pytest.fixture(scope="module")
def sight(house0):
    """A target on the floor and a direction from it along which the robot sees it from 0.5 m
    to 1.5 m: (target, unit direction (dx, dz))."""
    renderer = house0.built.renderer
    for x, z in reachable_grid(house0.built.house).points:
        target = (float(x), 0.0, float(z))  # a point of the open floor
        for angle in range(0, 360, 30):
            d = (math.sin(math.radians(angle)), math.cos(math.radians(angle)))
            origins = np.array([(x + r * d[0], ROBOT_CAMERA_HEIGHT, z + r * d[1]) for r in np.linspace(0.5, 1.5, 11)])
            if line_of_sight(renderer, origins, target).all():
                return target, d
    pytest.fail("house 0 has no open floor seen along a straight line")


def at(target, direction, metres: float) -> tuple[float, float]:
    return target[0] + metres * direction[0], target[2] + metres * direction[1]


def test_an_arrival_0_9_m_away_facing_the_target_succeeds(house0, sight):
    target, d = sight
    camera = facing(*at(target, d, 0.9), target)
    assert floor_distance(camera.position[0], camera.position[2], target) == pytest.approx(0.9)
    assert arrived(house0.built.renderer, camera, target)


def test_an_arrival_1_1_m_away_fails_though_the_target_is_in_view(house0, sight):
    target, d = sight
    camera = facing(*at(target, d, 1.1), target)
    assert in_view(house0.built.renderer, camera, target)
    assert not arrived(house0.built.renderer, camera, target)
    assert ARRIVAL_RADIUS == 1.0


def test_an_arrival_near_the_target_that_does_not_see_it_fails(house0, sight):
    target, d = sight
    ahead = facing(*at(target, d, 0.9), target)
    behind = Camera(ahead.position, (ahead.yaw + 180.0) % 360.0, ahead.horizon)
    assert not in_view(house0.built.renderer, behind, target)
    assert not arrived(house0.built.renderer, behind, target)


def test_a_target_hidden_behind_a_wall_is_not_in_view(house0):
    _, grid = house_floor(house0)
    renderer = house0.built.renderer
    cells = [grid.centre(c) for c in grid.cells()]
    # two reachable points 0.9 m apart on the floor with something solid between them
    for x, z in cells:
        for dx, dz in ((0.9, 0.0), (0.0, 0.9), (-0.9, 0.0), (0.0, -0.9)):
            target = (x + dx, 0.05, z + dz)
            camera = facing(x, z, target)
            if not line_of_sight(renderer, np.array([camera.position]), target)[0]:
                assert not arrived(renderer, camera, target)
                return
    pytest.fail("no occluded target found in house 0")


def test_the_goal_cells_of_the_shortest_path_are_arrivals(house0, sight):
    from povagent.active.navigation import goal_cells

    target, _ = sight
    _, grid = house_floor(house0)
    goals = goal_cells(grid, house0.built.renderer, target)
    assert goals
    for cell in goals:
        x, z = grid.centre(cell)
        assert arrived(house0.built.renderer, facing(x, z, target), target)

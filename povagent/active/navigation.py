"""The navigate task's ground truth on a generated house: arrival, the target in view, the
shortest reachable path.

What it is for: an episode of the navigate task ends where the robot says it has arrived. It
succeeds when that position lies within :data:`ARRIVAL_RADIUS` of the target on the floor and
the target is in view: projected inside the final camera's image, in front of it, and the first
thing the ray from the camera to it meets (the generator's renderer, :meth:`Renderer.first_hit`,
as the pairs check their anchors). SPL compares the path walked with the geodesic shortest path
(:mod:`.geodesic`) on the house's reachable floor, with the body and obstacles of ``move``
(:class:`~povagent.active.floor.Floor`), from the start to any cell within the radius from
which the target can be seen (turning and tilting are free). What it must not do: read a row,
a run folder or anything outside the house it is handed.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from povagent.active.floor import Floor
from povagent.active.geodesic import FloorGrid, GeodesicPath
from povagent.active.house import CACHE_SIZE, ActiveHouse, house_for
from povagent.active.pose import ROBOT_CAMERA_HEIGHT, Pose
from povagent.dataset.instances import Instance
from povagent.generate.exploration import CAMERA_HORIZON, reachable_grid
from povagent.generate.floorplan import GRID
from povagent.generate.renderer import Renderer
from povagent.geometry.camera import Camera
from povagent.scoring.normalized_l2 import project_ground_truth

#: How near the target (m, on the floor) an arrival must be.
ARRIVAL_RADIUS = 1.0
#: How far (m) before the target a surface on the ray may lie and still count as the target's
#: own (the target is a point on a surface: the ray ends on it).
VIEW_SLACK = 0.05
#: Shortest paths kept per process (a scorer asks once per row; a house has a few starts).
_PATHS_KEPT = 256


def floor_distance(x: float, z: float, target: Sequence[float]) -> float:
    """The distance (m) on the floor from (x, z) to the target's foot."""
    return math.hypot(float(target[0]) - x, float(target[2]) - z)


def line_of_sight(renderer: Renderer, origins: np.ndarray, target: Sequence[float]) -> np.ndarray:
    """Whether the target is the first thing met on the ray from each origin ((n, 3) points)."""
    origins = np.asarray(origins, dtype=float).reshape(-1, 3)
    to_target = np.asarray(target, dtype=float)[None] - origins
    distance = np.linalg.norm(to_target, axis=1)
    if len(origins) == 0:
        return np.zeros(0, dtype=bool)
    _, t = renderer.first_hit(origins, to_target / np.maximum(distance, 1e-9)[:, None])
    return np.asarray(t >= distance - VIEW_SLACK, dtype=bool)


def in_view(renderer: Renderer, camera: Camera, target: Sequence[float]) -> bool:
    """Whether ``camera`` sees the target: inside its image, in front of it, not occluded."""
    projected = project_ground_truth(tuple(float(v) for v in target), camera)  # type: ignore[arg-type]
    if projected.behind or not projected.in_frame:
        return False
    return bool(line_of_sight(renderer, np.asarray(camera.position, dtype=float)[None], target)[0])


def arrived(renderer: Renderer, camera: Camera, target: Sequence[float]) -> bool:
    """The navigate task's success: within :data:`ARRIVAL_RADIUS` on the floor, target in view."""
    x, _, z = (float(v) for v in camera.position)
    return floor_distance(x, z, target) <= ARRIVAL_RADIUS and in_view(renderer, camera, target)


def floor_grid(floor: Floor) -> FloorGrid:
    """The reachable cells of a house's floor as a grid, each step checked as ``move`` walks."""
    return FloorGrid.of_cells(floor.cells, GRID, floor.clear)


def goal_cells(grid: FloorGrid, renderer: Renderer, target: Sequence[float]) -> set[tuple[int, int]]:
    """The free cells within :data:`ARRIVAL_RADIUS` of the target from which a robot camera
    (at :data:`ROBOT_CAMERA_HEIGHT`) can see it once it turns and tilts towards it."""
    near = [c for c in grid.cells() if floor_distance(*grid.centre(c), target) <= ARRIVAL_RADIUS]
    if not near:
        return set()
    origins = np.array([(grid.centre(c)[0], ROBOT_CAMERA_HEIGHT, grid.centre(c)[1]) for c in near])
    return {c for c, seen in zip(near, line_of_sight(renderer, origins, target)) if seen}


_FLOORS: OrderedDict[tuple[str, str], tuple[Floor, FloorGrid]] = OrderedDict()
_PATHS: OrderedDict[tuple[str, str, tuple[float, ...]], GeodesicPath | None] = OrderedDict()
_LOCK = threading.Lock()


def house_floor(house: ActiveHouse) -> tuple[Floor, FloorGrid]:
    """The floor of a rebuilt house and its grid, built once per process (for as many houses
    as :mod:`.house` keeps)."""
    key = (str(house.dataset_dir), house.house_id)
    with _LOCK:
        kept = _FLOORS.get(key)
    if kept is None:
        floor = Floor(house.built.house)
        kept = (floor, floor_grid(floor))
        with _LOCK:
            kept = _FLOORS.setdefault(key, kept)
            while len(_FLOORS) > CACHE_SIZE:
                _FLOORS.popitem(last=False)
    return kept


def entrance_pose(house: ActiveHouse, like: Pose) -> Pose:
    """The robot standing just inside the entrance (the reachable cell the generator's tour
    starts from), at robot height and with the exploration frames' tilt, facing the house's
    middle; ``like`` gives the lens."""
    grid = reachable_grid(house.built.house)
    x, z = (float(v) for v in grid.points[grid.start])
    cx, cz = (float(v) for v in grid.points.mean(axis=0))
    yaw = round(math.degrees(math.atan2(cx - x, cz - z)) % 360.0, 3)
    return replace(like, x=round(x, 4), y=ROBOT_CAMERA_HEIGHT, z=round(z, 4), yaw=yaw, horizon=CAMERA_HORIZON)


def house_of(instance: Instance) -> ActiveHouse:
    """The rebuilt house of an instance of a povagent-generated dataset (its frames' folder
    says which dataset; the house must be one this generator version made)."""
    if not instance.frames:
        raise ValueError(f"{instance.id}: no frames to find its house by")
    return house_for(instance.frames[0].file.parent.parent.parent.parent, instance.house_id)


def shortest_arrival(house: ActiveHouse, start: tuple[float, float], target: Sequence[float]) -> GeodesicPath | None:
    """The geodesic shortest path from ``start`` (x, z) to a place where the target is reached
    and can be seen, or ``None`` when no such place is reachable (kept per process: a scorer
    and the oracle ask for the same one)."""
    key = (str(house.dataset_dir), house.house_id, (round(start[0], 4), round(start[1], 4), *(round(float(v), 4) for v in target)))
    with _LOCK:
        if key in _PATHS:
            _PATHS.move_to_end(key)
            return _PATHS[key]
    _, grid = house_floor(house)
    with house.lock:  # the renderer is used by one thread at a time
        goals = goal_cells(grid, house.built.renderer, target)
    found = grid.shortest(start, goals.__contains__)
    with _LOCK:
        _PATHS[key] = found
        while len(_PATHS) > _PATHS_KEPT:
            _PATHS.popitem(last=False)
    return found

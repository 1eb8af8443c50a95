"""A generated house as a robot's tour: the map is z-up, the mount is fixed, the cameras see what
the house's AI2-THOR cameras see."""

from __future__ import annotations

import numpy as np

from povagent.dataset.loader import load_dataset
from povagent.ros.house_tour import THOR_TO_MAP, well_seen_instance


def test_the_tours_cameras_project_a_point_where_the_houses_cameras_do(tour, generated_release):
    instance, _ = well_seen_instance(load_dataset(generated_release))
    point = np.asarray(instance.target, dtype=float)
    for camera, frame in zip(tour.cameras(), instance.frames):
        u, v, depth = frame.camera.project_point(point)
        if depth > 0.1:
            mu, mv, mdepth = camera.project_point(THOR_TO_MAP @ point)
            assert np.allclose((mu, mv, mdepth), (u, v, depth), atol=1e-9)


def test_the_base_stands_on_the_floor_and_the_mount_composes_to_the_camera(tour):
    for frame in tour.frames:
        assert frame.map_from_base.translation[2] == 0.0
        assert np.allclose(frame.map_from_base.matrix() @ tour.mount.matrix(), frame.map_from_camera, atol=1e-9)


def test_the_map_is_z_up_with_the_camera_above_the_floor_looking_down(tour):
    pose = tour.frames[0].map_from_camera
    assert pose[2, 3] > 0.5 and pose[2, 2] < 0  # optical z (forward) points a little down
    assert np.isclose(np.linalg.det(pose[:3, :3]), 1.0)  # a right-handed map

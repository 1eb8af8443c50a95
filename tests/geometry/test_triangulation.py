"""Locating a perceived object: rays met across views, against a height prior, and a box fit.

Synthetic cameras posed like the release's exploration frames (0.9 m high, 30 degrees down,
100 degree field of view) look at known points and boxes; what the geometry recovers from
their exact projections must be the truth, and each fallback must engage exactly when its
rule says.
"""

from __future__ import annotations

import numpy as np
import pytest

from povagent.geometry.camera import Camera
from povagent.geometry.triangulation import (
    MIN_RAY_ANGLE_DEG,
    Outline,
    Sighting,
    closest_point_to_rays,
    fit_box,
    locate,
    meet_height,
    projected_box,
)


def looking_at(position, target, horizon=30.0) -> Camera:
    """An exploration-style camera at ``position`` turned (yaw) towards ``target``."""
    d = np.asarray(target, dtype=float) - np.asarray(position, dtype=float)
    yaw = float(np.degrees(np.arctan2(d[0], d[2])))
    return Camera.from_pose(position, yaw, horizon)


def sighting(camera: Camera, point) -> Sighting:
    u, v, _ = camera.project_point(point)
    return Sighting(camera, (u * camera.width, v * camera.height))


POINT = (1.0, 0.45, 2.0)


def test_two_views_of_a_point_triangulate_to_it():
    cams = [looking_at((-1.0, 0.9, 0.0), POINT), looking_at((2.5, 0.9, -0.5), POINT)]
    est = locate([sighting(c, POINT) for c in cams], centre_height=2.0)  # a wrong prior: unused
    assert est.method == "triangulated" and est.views == 2
    assert np.allclose(est.point, POINT, atol=1e-6)


def test_nearly_parallel_rays_fall_back_to_the_height_prior():
    # two cameras 5 cm apart see the point along rays less than MIN_RAY_ANGLE_DEG apart
    cams = [looking_at((0.0, 0.9, -1.0), POINT), looking_at((0.05, 0.9, -1.0), POINT)]
    est = locate([sighting(c, POINT) for c in cams], centre_height=POINT[1])
    assert est.spread_deg < MIN_RAY_ANGLE_DEG and est.method == "height prior"
    assert np.allclose(est.point, POINT, atol=1e-6)


def test_one_view_meets_the_prior_height_on_the_pointed_ray():
    cam = looking_at((-1.0, 0.9, 0.0), POINT)
    est = locate([sighting(cam, POINT)], centre_height=0.3)  # the prior is 15 cm low
    assert est.method == "height prior" and est.point[1] == pytest.approx(0.3)
    u, v, _ = cam.project_point(est.point)
    assert (u * 512, v * 512) == pytest.approx(sighting(cam, POINT).pixel, abs=1e-6)


def test_a_ray_that_never_meets_the_prior_height_is_cut_and_says_so():
    cam = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 30.0)  # looking down: its rays never reach 2 m
    point, met = meet_height(Sighting(cam, (256.0, 256.0)), height=2.0)
    assert not met and np.linalg.norm(point - np.array(cam.position)) == pytest.approx(2.5)


def test_parallel_rays_have_no_closest_point():
    origins = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    dirs = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    assert closest_point_to_rays(origins, dirs) is None


CENTRE = np.array([1.0, 0.4, 2.5])
HALF = np.array([0.6, 0.4, 0.3])


def outlines(cams):
    return [Outline(c, projected_box(c, CENTRE, HALF)) for c in cams]


def test_box_outlines_from_three_views_give_the_box():
    cams = [looking_at(p, CENTRE) for p in ((-1.5, 0.9, 0.5), (3.5, 0.9, 0.8), (1.0, 0.9, -0.5))]
    box = fit_box(CENTRE, outlines(cams), prior_half=(0.3, 0.3, 0.3), centre_sigma=0.05)
    assert box.edges_used == 12
    assert np.allclose(box.half, HALF, atol=0.01) and np.allclose(box.centre, CENTRE, atol=0.01)
    assert box.top == pytest.approx(0.8, abs=0.01)


def test_box_edges_cut_by_the_image_border_are_left_out():
    cam = looking_at((-1.5, 0.9, 0.5), CENTRE)
    _x0, y0, x1, _y1 = projected_box(cam, CENTRE, HALF)
    clipped = Outline(cam, (0.0, y0, x1, 511.0))  # left and bottom edges at the border
    box = fit_box(CENTRE, [clipped], prior_half=tuple(HALF), centre_sigma=0.05)
    assert box.edges_used == 2


def test_without_a_usable_edge_the_prior_size_stands_in():
    cam = looking_at((-1.5, 0.9, 0.5), CENTRE)
    box = fit_box(CENTRE, [Outline(cam, (0.0, 0.0, 511.0, 511.0))], prior_half=(0.5, 0.25, 0.4))
    assert box.edges_used == 0 and box.half == (0.5, 0.25, 0.4)

"""``boundary_points`` (many directions at once, for the relation region) is the official
``boundary_point`` rule bit for bit, axis-aligned and degenerate directions included."""

from __future__ import annotations

import math
import warnings

import numpy as np

from povagent.geometry.ground_truth import AnchorBox, boundary_point, boundary_points

BOXES = [AnchorBox((2.0, -1.3), (0.5, 0.3), 1.0), AnchorBox((0.1, 0.7), (1.7, 0.05), 0.4), AnchorBox((-3.3, 2.2), (0.0, 0.4), 0.8)]


def directions() -> np.ndarray:
    rng = np.random.default_rng(0)
    angles = np.concatenate([rng.uniform(0, 2 * math.pi, 500), np.arange(0, 360, 5) * math.pi / 180])
    unit = np.stack([np.cos(angles), np.zeros_like(angles), np.sin(angles)], axis=1)
    special = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 0, 0], [1e-7, 0, 1e-7], [1e-7, 0, 0.8], [-0.6, 0, 1e-8]])
    # a component of exactly ZERO_LENGTH counts as none, as in the scalar rule
    at_threshold = np.array([[1e-6, 0, 0], [0, 0, -1e-6], [1e-6, 0, 0.8], [-0.5, 0, 1e-6], [1e-6, 0, 1e-6]])
    special = np.concatenate([special, at_threshold])
    return np.concatenate([unit, special])


def test_every_direction_gives_the_official_rules_point_to_the_bit():
    d = directions()
    for box in BOXES:
        xs, zs = boundary_points(box, d)
        for k, direction in enumerate(d):
            bx, bz = boundary_point(box, direction)
            assert (xs[k], zs[k]) == (bx, bz), (box, direction)


def test_a_direction_without_an_xz_part_stays_at_the_centre_not_nan():
    xs, zs = boundary_points(BOXES[0], np.array([[0.0, 0.0, 0.0]]))
    assert (xs[0], zs[0]) == (2.0, -1.3)  # 0.3 m along a zero direction: the centre itself


def test_a_flat_box_and_zero_directions_give_no_warning_and_no_nan():
    # a box without depth along an axis (half size 0) and directions without that component: no
    # 0/0 is ever computed, so nothing warns and every point is a number
    box = AnchorBox((1.0, -2.0), (0.0, 0.0), 0.5)
    d = np.array([[0.0, 0, 0], [1.0, 0, 0], [0, 0, 1.0], [1e-7, 0, 0], [0.6, 0, 0.8]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        xs, zs = boundary_points(box, d)
    assert np.isfinite(xs).all() and np.isfinite(zs).all()
    assert [(bx, bz) for bx, bz in zip(xs.tolist(), zs.tolist())] == [tuple(boundary_point(box, v).tolist()) for v in d]

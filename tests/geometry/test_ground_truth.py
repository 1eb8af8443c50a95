"""Ground-truth placement rules, checked against points worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.geometry.ground_truth import (
    AnchorBox,
    anchor_keywords,
    boundary_point,
    direction_vectors,
    surface_names_anchor,
    target_point,
)

# A 2 x 0.6 x 2 bed centred at (0, 0.3, 3); the observer camera at the origin looks along +z.
BED = AnchorBox(center_xz=(0.0, 3.0), half_xz=(1.0, 1.0), top=0.6)
BED_POS = np.array([0.0, 0.3, 3.0])
OBSERVER = np.array([0.0, 1.5, 0.0])


def gt(direction, surface, verdict="appropriate", anchor="Bed", box=BED, pos=BED_POS, raw=(9, 9, 9)):
    return target_point(direction, box, anchor, pos, OBSERVER, verdict, surface, np.array(raw, float))


def test_up_is_above_the_box_centre_by_the_half_cube():
    assert np.allclose(gt("up", "on the bed"), [0.0, 0.8, 3.0])


def test_front_on_the_floor_is_past_the_near_face_towards_the_observer():
    # near face at z = 2, plus 0.2 towards the observer; floor + 0.2
    assert np.allclose(gt("front", "on the floor"), [0.0, 0.2, 1.8])


def test_left_on_a_flat_topped_anchor_sits_on_it_offset_from_the_centre():
    # facing +z, left is -x: centre + 0.2 left, on top + 0.2
    assert np.allclose(gt("left", "on the bed"), [-0.2, 0.8, 3.0])


def test_right_beside_a_flat_topped_anchor_on_the_floor_uses_the_boundary():
    assert np.allclose(gt("right", "on the floor"), [1.2, 0.2, 3.0])


def test_left_of_a_non_flat_anchor_uses_the_boundary_even_if_the_surface_names_it():
    assert np.allclose(gt("left", "on the sofa", anchor="Sofa"), [-1.2, 0.8, 3.0])


def test_surface_naming_another_object_uses_the_anchor_top():
    assert np.allclose(gt("front", "on the side table"), [0.0, 0.8, 1.8])


def test_an_inappropriate_verdict_keeps_the_raw_placement():
    assert np.allclose(gt("front", "on the floor", verdict="inappropriate", raw=(1, 2, 3)), [1, 2, 3])


def test_diagonal_view_leaves_the_box_through_the_nearer_face():
    # sofa 2 x 1 at (3, 3), observer at the origin: fwd = (1, 0, 1)/sqrt2, front = -fwd
    box = AnchorBox((3.0, 3.0), (1.0, 0.5), 0.8)
    s = 1 / math.sqrt(2)
    front = gt("front", "on the floor", anchor="Sofa", box=box, pos=np.array([3.0, 0.4, 3.0]))
    # t = min(1/s, 0.5/s) = 0.5*sqrt2 -> boundary (2.5, 2.5); then 0.2 further along front
    assert np.allclose(front, [2.5 - 0.2 * s, 0.2, 2.5 - 0.2 * s])


def test_right_is_world_up_cross_forward():
    dirs = direction_vectors(np.array([0.0, 0, 1]), np.zeros(3))
    assert np.allclose(dirs["right"], [1, 0, 0])
    assert np.allclose(dirs["left"], [-1, 0, 0])
    assert np.allclose(dirs["front"], [0, 0, -1])


def test_boundary_of_a_zero_direction_stays_at_the_box_centre():
    assert np.allclose(boundary_point(BED, np.zeros(3)), [0.0, 3.0])


@pytest.mark.parametrize(
    "surface, anchor, expected",
    [
        ("on the couch", "Sofa", True),
        ("on the refrigerator", "Fridge", True),
        ("on the arm chair", "ArmChair", True),
        ("on the kitchen counter", "CounterTop", True),
        ("on the coffee table", "CoffeeTable", True),
        ("on the bed", "Bed", True),
        ("on the shelving unit", "ShelvingUnit", True),
        ("on the floor", "Bed", False),
        ("on the table", "DiningTable", False),
    ],
)
def test_surface_keyword_match(surface, anchor, expected):
    assert surface_names_anchor(surface, anchor) is expected


def test_camelcase_types_split_into_words():
    assert anchor_keywords("ShelvingUnit") == ("shelving unit",)


def test_a_direction_component_below_1e_minus_6_is_ignored_by_the_boundary_rule_as_officially():
    # a box with no x extent: dx = 5e-7 would give t = hx/dx = 0 if it counted; officially t = hz/dz
    flat = AnchorBox(center_xz=(0.0, 3.0), half_xz=(0.0, 1.0), top=0.6)
    d = np.array([5e-7, 0.0, 1.0])
    assert np.allclose(boundary_point(flat, d), [5e-7, 4.0], atol=1e-12)


def test_an_anchor_straight_below_the_observer_gives_zero_directions_as_officially():
    # the official scorer leaves a vector of length <= 1e-6 unnormalized: no direction at all,
    # so the front target stays at the box centre (boundary distance 0.3 along a zero vector)
    dirs = direction_vectors(np.array([0.0, 0.3, 3.0]), np.array([0.0, 1.5, 3.0]))
    assert np.allclose(dirs["front"], 0.0) and np.allclose(dirs["right"], 0.0)
    over = np.array([0.0, 1.5, 3.0])
    target = target_point("front", BED, "Bed", BED_POS, over, "appropriate", "on the floor", np.zeros(3))
    assert np.allclose(target, [0.0, 0.2, 3.0])


def test_types_outside_the_table_split_at_capitals_only_as_officially():
    assert anchor_keywords("TVStand") == ("t v stand",)
    assert anchor_keywords("tvStand") == ("stand",)
    assert anchor_keywords("Chair") == ("chair",) and anchor_keywords("Sink") == ("sink",)

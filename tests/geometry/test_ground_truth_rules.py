"""The surface-corrected GT rules, one per test, each failing if the rule is bent.

Facts (POVBENCH.md, "Ground truth the official scorer uses"): only a verdict of exactly
"appropriate" is corrected, anything else (a missing verdict too) keeps placements[dir].position;
fwd = normalize(anchor - observer) with y zeroed, right = world_up x fwd, left = -right,
front = -fwd; b(d) = c + t d with t = min(hx/|dx|, hz/|dz|) over nonzero components (0.3 if both
are zero); up = (c.x, top + 0.2, c.z); front and left/right beside the anchor: b(d) + 0.2 d at
y_surf + 0.2; left/right on a flat-topped anchor (G) whose surface names it: c + 0.2 d at
top + 0.2; y_surf is 0 when the lower-cased surface contains "floor", else the anchor's top.

Here the observer stands at the origin and the anchor at x = 3 (fwd = +x), so that
right = world_up x (1, 0, 0) = (0, 0, -1) and left = (0, 0, 1): the offsets of left and right
lie along z, where a wrong sign shows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.geometry.ground_truth import (
    DEGENERATE_BOUNDARY_DISTANCE,
    FLAT_TOPPED_ANCHORS,
    TARGET_HALF_SIZE,
    ZERO_LENGTH,
    AnchorBox,
    PlacementCase,
    boundary_point,
    direction_vectors,
    stands_on_anchor,
    surface_height,
    target_point,
)

# a 1.0 (x) by 0.8 (z) table, 0.7 high, centred at (3, 0.35, 0.5)
TABLE = AnchorBox(center_xz=(3.0, 0.5), half_xz=(0.5, 0.4), top=0.7)
ANCHOR = np.array([3.0, 0.35, 0.0])
OBSERVER = np.array([0.0, 1.5, 0.0])
RAW = np.array([7.0, 8.0, 9.0])


def gt(direction, surface, anchor_type="DiningTable", verdict="appropriate"):
    return target_point(direction, TABLE, anchor_type, ANCHOR, OBSERVER, verdict, surface, RAW)


def test_the_target_cube_is_0_4_m_so_offsets_are_0_2_m():
    assert TARGET_HALF_SIZE == 0.2


@pytest.mark.parametrize("verdict", [None, "inappropriate", "Appropriate ", "unclear"])
def test_only_an_appropriate_verdict_is_surface_corrected(verdict):
    assert np.array_equal(gt("front", "on the floor", verdict=verdict), RAW)
    assert np.array_equal(gt("up", "on the dining table", verdict=verdict), RAW)


def test_right_is_world_up_cross_forward_and_left_its_opposite():
    d = direction_vectors(ANCHOR, OBSERVER)
    assert np.allclose(d["right"], [0.0, 0.0, -1.0])
    assert np.allclose(d["left"], [0.0, 0.0, 1.0])
    assert np.allclose(d["front"], [-1.0, 0.0, 0.0])


def test_directions_ignore_the_height_difference():
    d = direction_vectors(np.array([3.0, 10.0, 4.0]), np.array([0.0, -2.0, 0.0]))
    assert np.allclose(d["front"], [-0.6, 0.0, -0.8])
    assert np.allclose(d["right"], [0.8, 0.0, -0.6])


def test_up_is_above_the_box_centre():
    assert np.allclose(gt("up", "on the floor"), [3.0, 0.7 + 0.2, 0.5])


def test_left_on_a_flat_topped_anchor_is_offset_from_the_centre_along_left():
    assert np.allclose(gt("left", "on the dining table"), [3.0, 0.9, 0.5 + 0.2])


def test_right_on_a_flat_topped_anchor_is_offset_from_the_centre_along_right():
    assert np.allclose(gt("right", "on the dining table"), [3.0, 0.9, 0.5 - 0.2])


def test_left_beside_the_anchor_on_the_floor_is_past_its_boundary():
    # left = +z: leaves the box at z = 0.5 + 0.4, then 0.2 more; floor -> y = 0.2
    assert np.allclose(gt("left", "on the floor"), [3.0, 0.2, 0.5 + 0.4 + 0.2])


def test_front_on_the_floor_is_past_the_near_face_towards_the_observer():
    assert np.allclose(gt("front", "on the floor"), [3.0 - 0.5 - 0.2, 0.2, 0.5])


def test_front_on_another_object_stands_at_the_anchor_top():
    assert np.allclose(gt("front", "on the chair"), [2.3, 0.9, 0.5])


@pytest.mark.parametrize("surface", ["On the Floor", "FLOOR", "on the floor mat"])
def test_floor_is_recognised_in_any_case(surface):
    assert surface_height(surface, TABLE) == 0.0
    assert gt("front", surface)[1] == pytest.approx(0.2)


def test_no_surface_means_the_anchor_top():
    assert surface_height(None, TABLE) == 0.7


def test_the_surface_names_the_anchor_in_any_case():
    assert np.allclose(gt("left", "On The DINING TABLE"), [3.0, 0.9, 0.7])


def test_an_anchor_outside_the_flat_topped_set_never_holds_a_left_right_target():
    assert "Sofa" not in FLAT_TOPPED_ANCHORS
    assert np.allclose(gt("left", "on the sofa", anchor_type="Sofa"), [3.0, 0.9, 1.1])


def test_the_flat_topped_set_is_the_official_one():
    assert {"Bed", "CounterTop", "Desk", "Desktop", "DiningTable", "Dresser", "SideTable"} == FLAT_TOPPED_ANCHORS


def test_front_is_never_on_the_anchor_even_when_the_surface_names_it():
    assert np.allclose(gt("front", "on the dining table"), [2.3, 0.9, 0.5])


def test_the_boundary_takes_the_nearer_face():
    box = AnchorBox(center_xz=(0.0, 0.0), half_xz=(1.0, 0.5), top=1.0)
    d = np.array([0.6, 0.0, 0.8])
    # t = min(1/0.6, 0.5/0.8) = 0.625 -> (0.375, 0.5)
    assert np.allclose(boundary_point(box, d), [0.375, 0.5])
    assert np.allclose(boundary_point(box, -d), [-0.375, -0.5])


def test_the_boundary_along_one_axis_uses_that_axis_half_size():
    box = AnchorBox(center_xz=(1.0, 2.0), half_xz=(0.3, 0.7), top=1.0)
    assert np.allclose(boundary_point(box, np.array([0.0, 0.0, -1.0])), [1.0, 1.3])
    assert np.allclose(boundary_point(box, np.array([-1.0, 0.0, 0.0])), [0.7, 2.0])


def test_a_zero_direction_leaves_the_box_at_0_3_m():
    assert DEGENERATE_BOUNDARY_DISTANCE == 0.3
    box = AnchorBox(center_xz=(1.0, 2.0), half_xz=(0.3, 0.7), top=1.0)
    assert np.allclose(boundary_point(box, np.zeros(3)), [1.0, 2.0])


def test_directions_of_an_anchor_closer_than_a_metre_are_still_its_direction():
    d = direction_vectors(np.array([0.3, 0.5, 0.4]), np.array([0.0, 1.5, 0.0]))
    assert np.allclose(d["front"], [-0.6, 0.0, -0.8])


def test_directions_are_zero_not_nan_with_the_anchor_straight_below_the_observer():
    # as officially: a horizontal offset of at most 1e-6 is not normalized (no division by
    # zero), so every direction is the zero vector and the target sits at the anchor's centre
    d = direction_vectors(np.array([1.0, 0.5, 2.0]), np.array([1.0, 1.5, 2.0]))
    for v in d.values():
        assert np.all(np.isfinite(v)) and v[1] == 0.0
        assert np.linalg.norm(v) == 0.0


def test_a_tiny_but_real_horizontal_offset_is_still_normalized():
    d = direction_vectors(np.array([1.0 + 1e-5, 0.5, 2.0]), np.array([1.0, 1.5, 2.0]))
    assert np.linalg.norm(d["front"]) == pytest.approx(1.0) and np.linalg.norm(d["right"]) == pytest.approx(1.0)


def test_an_offset_or_a_component_of_exactly_1e_6_counts_as_none():
    # "no longer than 1e-6" is inclusive: the offset is left as it is (not normalized), and the
    # boundary rule sees no component in the directions, so every target stays at the centre
    # (0.3 m along a 1e-6 vector), not on a face of the box
    assert ZERO_LENGTH == 1e-6
    d = direction_vectors(np.array([1e-6, 0.5, 0.0]), np.array([0.0, 1.5, 0.0]))
    assert d["front"].tolist() == [-1e-6, 0.0, 0.0]
    assert d["right"].tolist() == [0.0, 0.0, -1e-6] and d["left"].tolist() == [0.0, 0.0, 1e-6]
    box = AnchorBox(center_xz=(0.0, 0.0), half_xz=(0.5, 0.4), top=0.7)
    for v in d.values():
        assert np.allclose(boundary_point(box, v), [0.0, 0.0], rtol=0.0, atol=1e-6)


def test_right_is_divided_by_its_length_as_officially_to_the_bit():
    # fwd's turn is not always exactly unit long (here hypot gives 1 - 1 ulp): the official
    # code divides it by its length, and the GT must carry the same bits
    anchor, observer = np.array([3.3576510391986965, 0.0, -0.6723293209494665]), np.zeros(3)
    n = math.hypot(anchor[0], anchor[2])
    fx, fz = anchor[0] / n, anchor[2] / n
    rn = math.hypot(fz, -fx)
    assert rn != 1.0
    assert direction_vectors(anchor, observer)["right"].tolist() == [fz / rn, 0.0, -fx / rn]


def test_forward_runs_from_the_observer_to_the_anchor_wherever_the_observer_stands():
    d = direction_vectors(np.array([4.0, 0.0, 5.0]), np.array([1.0, 1.5, 1.0]))
    assert np.allclose(d["front"], [-0.6, 0.0, -0.8])
    assert np.allclose(d["right"], [0.8, 0.0, -0.6])


@pytest.mark.parametrize(("verdict", "applies"), [("appropriate", True), ("inappropriate", False), (None, False), ("", False), ("Appropriate", False)])
def test_a_placement_case_applies_the_rules_only_for_exactly_appropriate(verdict, applies):
    c = PlacementCase("left", TABLE, "DiningTable", tuple(ANCHOR), (3.0, 0.35, 0.5), tuple(OBSERVER), verdict, "on the floor", tuple(RAW))
    assert c.rules_apply is applies
    assert np.array_equal(c.target(), gt("left", "on the floor", verdict=verdict))


def test_an_on_top_direction_always_stands_on_the_anchor():
    # whatever the anchor and the surface said: the registry's "up" is on the anchor's top
    assert stands_on_anchor("up", "Fridge", None) is True


def test_a_direction_outside_the_registry_never_stands_on_the_anchor():
    assert stands_on_anchor("diagonal", "Bed", "on the bed") is False


def test_a_lateral_target_stands_on_a_flat_topped_anchor_the_surface_names():
    assert stands_on_anchor("left", "Bed", "on the bed") is True
    assert stands_on_anchor("front", "Bed", "on the bed") is False
    assert stands_on_anchor("left", "Sofa", "on the sofa") is False

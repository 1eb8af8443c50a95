"""Condition C in the image plane: the observer view, no pose.

A synthetic observer view (eye height, looking down a little) of an anchor of its type's usual
size: from the exact projections the solver must put the target where the benchmark's rules
put it; the anchor's centre is read from both the pointed centre and the box.
"""

from __future__ import annotations

import numpy as np
import pytest

from povagent.geometry.camera import Camera
from povagent.geometry.given_view import BOX_CENTRE_WEIGHT, EYE_HEIGHT, anchor_centre, solve_given_view
from povagent.geometry.placement import AnchorEstimate, place_target
from povagent.geometry.size_priors import size_prior
from povagent.geometry.triangulation import projected_box

#: A near-square footprint: whether the box's width is the anchor's width or depth (a guess
#: the solver must make from one view) hardly matters, so the rest of the geometry shows.
ANCHOR = "SideTable"


def test_without_a_box_the_pointed_centre_is_the_anchors_centre():
    assert anchor_centre((100.0, 200.0), None) == (100.0, 200.0)


def test_the_box_centre_weighs_twice_the_pointed_centre():
    assert BOX_CENTRE_WEIGHT == 2.0
    assert anchor_centre((100.0, 200.0), (190.0, 260.0, 250.0, 320.0)) == pytest.approx((180.0, 260.0))


def test_reading_the_centre_from_both_answers_halves_the_pointing_noise_or_better():
    rng = np.random.default_rng(0)
    truth = np.array([256.0, 300.0])
    box = np.array([206.0, 260.0, 306.0, 340.0])  # centred on the truth
    pointed_err, fused_err = [], []
    for _ in range(4000):
        point = truth + rng.normal(0.0, 40.0, 2)
        noisy_box = box + rng.normal(0.0, 40.0, 4)
        pointed_err.append(np.sum((point - truth) ** 2))
        fused_err.append(np.sum((np.array(anchor_centre(tuple(point), tuple(noisy_box))) - truth) ** 2))
    # independent noise of equal size: the weighted mean has a third of the pointed variance
    assert np.mean(fused_err) / np.mean(pointed_err) == pytest.approx(1 / 3, rel=0.1)


@pytest.mark.parametrize("direction", ["right", "left", "front"])
def test_exact_perception_of_a_usual_sized_anchor_gives_the_rules_target(direction):
    prior = size_prior(ANCHOR)
    view = Camera((0.0, EYE_HEIGHT, 0.0), 0.0, 20.0)  # the observer's view: yaw 0, looking down 20 degrees
    half = np.array([prior.size[0] / 2.0, prior.half_height, prior.size[2] / 2.0])
    centre = np.array([0.3, prior.centre_height, 3.0])
    u, v, _ = view.project_point(centre)
    box = projected_box(view, centre, half)
    solution = solve_given_view(direction, ANCHOR, prior, (u * 512, v * 512), box, "floor")
    target = place_target(direction, AnchorEstimate(tuple(centre), tuple(half)), ANCHOR, view.position, "floor")
    tu, tv, _ = view.project_point(target)
    assert solution.fitted and solution.tilt_deg == pytest.approx(20.0, abs=1.0)
    # a few px of 512: the box's centre is not exactly the projected 3D centre
    assert np.hypot(solution.pixel[0] - tu * 512, solution.pixel[1] - tv * 512) < 5.0

"""The official metric's rules, one per test, each failing if the rule is bent.

Facts (POVBENCH.md, "Metric" and "Camera"): normalized L2 = sqrt((x/W - gx)^2 + (y/H - gy)^2)
with prediction and GT both clamped to [0, 1]; x is divided by the width and y by the height; a
GT behind the camera (depth <= 1e-6) is placed at (0.5, 0.5) and counted out of frame; "in frame"
needs both u and v in [0, 1]; the strict variant counts a GT behind or outside the frame as a
miss (sqrt 2); a missing or unknown selected frame (a negative index included) leaves the row
unanswered; for several points the centroid is scored and the closest point's error is kept.

Cameras here sit at the origin looking down +z (yaw 0, horizon 0) with fov 90, so a point
(x, y, z) in front lands at u = 0.5 + 0.5 x/z, v = 0.5 - 0.5 y/z (square frames).
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.geometry.camera import Camera
from povagent.scoring.normalized_l2 import (
    MAX_L2,
    GroundTruthInFrame,
    OfficialScore,
    normalized_l2,
    project_ground_truth,
    score_point,
    scoring_frame,
    signed_errors,
    strict_l2,
)
from povagent_plugins.scorers.official_scorer import OfficialScorer

FRONT_CAMERA = Camera.from_pose((0.0, 0.0, 0.0), yaw=0.0, horizon=0.0, fov=90.0)


# -- normalisation and clamping -----------------------------------------------------------------
def test_x_is_divided_by_the_width_and_y_by_the_height():
    # 640x480: the centre pixel (320, 240) is (0.5, 0.5) only if y is divided by H
    assert normalized_l2(320.0, 240.0, 640, 480, 0.5, 0.5) == 0.0
    assert normalized_l2(640.0, 0.0, 640, 480, 1.0, 0.0) == 0.0
    assert normalized_l2(0.0, 480.0, 640, 480, 0.0, 1.0) == 0.0


def test_the_error_is_the_euclidean_distance_in_image_fractions():
    assert normalized_l2(0.0, 0.0, 512, 512, 0.3, 0.4) == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize(("x", "y"), [(-100.0, 256.0), (256.0, -100.0), (900.0, 256.0), (256.0, 900.0)])
def test_a_prediction_outside_the_frame_is_clamped_to_its_edge(x, y):
    edge_x, edge_y = min(max(x / 512, 0.0), 1.0), min(max(y / 512, 0.0), 1.0)
    assert normalized_l2(x, y, 512, 512, 0.5, 0.5) == pytest.approx(math.hypot(edge_x - 0.5, edge_y - 0.5), abs=1e-12)


@pytest.mark.parametrize(("gu", "gv", "clamped"), [(1.7, 0.5, (1.0, 0.5)), (-0.4, 0.5, (0.0, 0.5)), (0.5, 2.0, (0.5, 1.0)), (0.5, -3.0, (0.5, 0.0))])
def test_a_gt_outside_the_frame_is_clamped_to_its_edge(gu, gv, clamped):
    assert normalized_l2(256.0, 256.0, 512, 512, gu, gv) == pytest.approx(math.hypot(0.5 - clamped[0], 0.5 - clamped[1]), abs=1e-12)


def test_the_largest_error_is_the_diagonal_sqrt2():
    assert math.sqrt(2.0) == MAX_L2
    assert normalized_l2(0.0, 0.0, 512, 512, 1.0, 1.0) == pytest.approx(math.sqrt(2.0), abs=1e-12)


# -- the GT in a camera --------------------------------------------------------------------------
def test_gt_in_front_projects_through_the_pinhole():
    gt = project_ground_truth((1.0, 0.5, 2.0), FRONT_CAMERA)
    assert (gt.u, gt.v) == pytest.approx((0.75, 0.375), abs=1e-12)
    assert gt.in_frame and not gt.behind


@pytest.mark.parametrize("point", [(0.0, 1.2, 1.0), (0.0, -1.2, 1.0)])
def test_gt_above_or_below_the_frame_is_out_of_frame_even_when_u_is_inside(point):
    gt = project_ground_truth(point, FRONT_CAMERA)
    assert 0.0 <= gt.u <= 1.0
    assert not gt.in_frame
    assert not gt.behind


@pytest.mark.parametrize("point", [(1.2, 0.0, 1.0), (-1.2, 0.0, 1.0)])
def test_gt_left_or_right_of_the_frame_is_out_of_frame(point):
    gt = project_ground_truth(point, FRONT_CAMERA)
    assert 0.0 <= gt.v <= 1.0
    assert not gt.in_frame


def test_gt_on_the_top_left_corner_is_in_frame():
    f = FRONT_CAMERA.focal_px
    gt = project_ground_truth((-256.0 / f, 256.0 / f, 1.0), FRONT_CAMERA)
    assert (gt.u, gt.v) == (0.0, 0.0)
    assert gt.in_frame


def test_gt_on_the_frame_edge_is_in_frame():
    # x/z = 1 -> u = 1 exactly; y/z = -1 -> v = 1 exactly
    assert project_ground_truth((1.0, 0.0, 1.0), FRONT_CAMERA).in_frame
    assert project_ground_truth((0.0, -1.0, 1.0), FRONT_CAMERA).in_frame


@pytest.mark.parametrize("depth", [-2.0, 0.0, 1e-6])
def test_gt_at_or_behind_the_camera_is_placed_at_the_centre_and_out_of_frame(depth):
    gt = project_ground_truth((0.3, 0.2, depth), FRONT_CAMERA)
    assert (gt.u, gt.v, gt.in_frame, gt.behind) == (0.5, 0.5, False, True)


def test_gt_just_past_the_behind_threshold_is_projected():
    gt = project_ground_truth((0.0, 0.0, 2e-6), FRONT_CAMERA)
    assert not gt.behind and gt.in_frame


def test_a_gt_and_a_score_are_values_that_cannot_be_altered():
    gt = project_ground_truth((0.0, 0.0, 2.0), FRONT_CAMERA)
    with pytest.raises(dataclasses.FrozenInstanceError):
        gt.u = 0.0  # type: ignore[misc]
    score = OfficialScore(True, 0.1, 0.1, True, False, 0.5, 0.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        score.l2 = 0.0  # type: ignore[misc]


# -- the strict variant -------------------------------------------------------------------------
def test_strict_l2_counts_a_gt_outside_the_frame_as_a_miss():
    out = GroundTruthInFrame(0.5, 1.4, in_frame=False, behind=False)
    assert strict_l2(256.0, 512.0, 512, 512, out) == math.sqrt(2.0)


def test_strict_l2_counts_a_gt_behind_the_camera_as_a_miss():
    behind = GroundTruthInFrame(0.5, 0.5, in_frame=False, behind=True)
    assert strict_l2(256.0, 256.0, 512, 512, behind) == math.sqrt(2.0)


def test_strict_l2_equals_the_official_error_for_a_gt_in_frame():
    inside = GroundTruthInFrame(0.25, 0.75, in_frame=True, behind=False)
    assert strict_l2(0.0, 0.0, 640, 480, inside) == normalized_l2(0.0, 0.0, 640, 480, 0.25, 0.75)


# -- the signed errors (what the official mean_abs_x / mean_abs_y average) ---------------------
def test_the_signed_errors_are_the_clamped_prediction_minus_the_clamped_gt():
    # 640x480: x is divided by W and y by H; the sign says on which side of the GT the point is
    assert signed_errors(160.0, 360.0, 640, 480, 0.5, 0.5) == pytest.approx((-0.25, 0.25), abs=1e-12)
    assert signed_errors(480.0, 120.0, 640, 480, 0.25, 0.75) == pytest.approx((0.5, -0.5), abs=1e-12)
    # both the prediction and the GT are clamped to [0, 1] first
    assert signed_errors(-50.0, 900.0, 640, 480, 1.4, -0.2) == pytest.approx((-1.0, 1.0), abs=1e-12)


def clamped(v):
    return min(1.0, max(0.0, v))


def test_a_score_records_the_signed_errors_of_the_recorded_point(mini_dataset):
    given = mini_dataset.instance("train_house_00000/0/up/c")
    frame = given.frames[0]
    w, h = frame.camera.width, frame.camera.height
    gt = project_ground_truth(given.target, frame.camera)
    s = score_point(given, frame, 0.25 * w, 0.75 * h)
    assert (s.error_x, s.error_y) == pytest.approx((0.25 - clamped(gt.u), 0.75 - clamped(gt.v)), abs=1e-12)
    # a recorded point other than the scored one (a point list's first point): its errors, the scored point's l2
    r = score_point(given, frame, 0.25 * w, 0.75 * h, (0.9 * w, 0.1 * h))
    assert (r.error_x, r.error_y) == pytest.approx((0.9 - clamped(gt.u), 0.1 - clamped(gt.v)), abs=1e-12)
    assert r.l2 == s.l2


# -- which frame, and who is answered -----------------------------------------------------------
@pytest.fixture
def inferred(mini_dataset):
    return mini_dataset.instance("train_house_00000/0/up/a")


def test_a_negative_selected_image_is_no_frame(inferred):
    assert len(inferred.frames) >= 2
    assert scoring_frame(inferred, -1) is None
    assert scoring_frame(inferred, len(inferred.frames)) is None
    assert scoring_frame(inferred, None) is None
    assert scoring_frame(inferred, len(inferred.frames) - 1) is inferred.frames[-1]


def test_a_row_with_a_negative_selected_image_is_unanswered(inferred):
    answer = ParsedAnswer(status=ParseStatus.OK, selected_image=-1, x=256.0, y=256.0)
    scores = OfficialScorer().score(inferred, answer)
    assert scores["answered"] is False and scores["l2"] is None


def test_an_unknown_frame_path_is_no_frame(inferred):
    assert scoring_frame(inferred, image_path="exploration_images/missing.png") is None
    assert scoring_frame(inferred, image_path=inferred.frames[1].image_path) is inferred.frames[1]


def test_given_is_scored_in_the_observer_view_whatever_frame_is_named(mini_dataset):
    given = mini_dataset.instance("train_house_00000/0/up/c")
    assert scoring_frame(given, 5) is given.frames[0]


def test_an_answer_without_a_frame_is_unanswered_with_the_reason(inferred):
    s = score_point(inferred, None, 10.0, 10.0)
    assert not s.answered and s.l2 is None
    assert "frame" in s.reason


@pytest.mark.parametrize(("x", "y"), [(None, 3.0), (3.0, None)])
def test_a_missing_coordinate_is_unanswered(inferred, x, y):
    s = score_point(inferred, inferred.frames[0], x, y)
    assert not s.answered and s.l2 is None


def test_a_nan_coordinate_is_answered_with_a_nan_error_as_officially(inferred):
    # the official scorer records it and its mean turns NaN (povagent names such rows in a warning)
    s = score_point(inferred, inferred.frames[0], math.nan, 3.0)
    assert s.answered and math.isnan(s.l2)


def test_an_infinite_coordinate_is_clamped_to_the_edge_as_officially(inferred):
    frame = inferred.frames[0]
    w = frame.camera.width
    at_infinity = score_point(inferred, frame, 3.0, math.inf)
    at_the_edge = score_point(inferred, frame, 3.0, 10.0 * frame.camera.height)
    assert at_infinity.answered and at_infinity.l2 == at_the_edge.l2
    assert score_point(inferred, frame, -math.inf, 3.0).l2 == score_point(inferred, frame, -10.0 * w, 3.0).l2


def test_the_selected_frame_is_the_one_scored(inferred):
    moved = dataclasses.replace(inferred, target=(0.0, 0.9, 3.0))
    for k, frame in enumerate(moved.frames):
        scores = OfficialScorer().score(moved, ParsedAnswer(status=ParseStatus.OK, selected_image=k, x=0.0, y=0.0))
        gt = project_ground_truth(moved.target, frame.camera)
        assert scores["gt_u"] == gt.u and scores["gt_v"] == gt.v


# -- the scorer plugin ---------------------------------------------------------------------------
def test_the_scorer_reports_the_centroid_and_keeps_the_closest_point(mini_dataset):
    given = mini_dataset.instance("train_house_00000/0/up/c")
    gt = project_ground_truth(given.target, given.frames[0].camera)
    near = (gt.u * 512, gt.v * 512)
    far = (0.0, 0.0)
    centroid = ((near[0] + far[0]) / 2, (near[1] + far[1]) / 2)
    answer = ParsedAnswer(status=ParseStatus.OK, x=centroid[0], y=centroid[1], points=[near, far])
    scores = OfficialScorer().score(given, answer)
    assert scores["l2"] == pytest.approx(normalized_l2(*centroid, 512, 512, gt.u, gt.v), abs=1e-12)
    assert scores["l2_closest"] == pytest.approx(0.0, abs=1e-12)


def test_the_scorer_records_a_point_lists_first_point_as_the_official_runner_does(mini_dataset):
    # the official runner writes the first point as predicted_x/y: the signed errors are its,
    # the error l2 the centroid's
    given = mini_dataset.instance("train_house_00000/0/up/c")
    gt = project_ground_truth(given.target, given.frames[0].camera)
    first, last = (100.0, 200.0), (400.0, 50.0)
    centroid = ((first[0] + last[0]) / 2, (first[1] + last[1]) / 2)
    scores = OfficialScorer().score(given, ParsedAnswer(status=ParseStatus.OK, x=centroid[0], y=centroid[1], points=[first, last]))
    expected = (clamped(100.0 / 512) - clamped(gt.u), clamped(200.0 / 512) - clamped(gt.v))
    assert (scores["error_x"], scores["error_y"]) == pytest.approx(expected, abs=1e-12)
    assert scores["l2"] == pytest.approx(normalized_l2(*centroid, 512, 512, gt.u, gt.v), abs=1e-12)


def test_a_single_point_answer_has_no_closest_point_entry(mini_dataset):
    given = mini_dataset.instance("train_house_00000/0/up/c")
    scores = OfficialScorer().score(given, ParsedAnswer(status=ParseStatus.OK, x=1.0, y=2.0, points=[(1.0, 2.0)]))
    assert "l2_closest" not in scores
    assert scores["answered"] is True


def test_the_scorer_gives_an_unparsed_answer_no_score(mini_dataset):
    given = mini_dataset.instance("train_house_00000/0/up/c")
    scores = OfficialScorer().score(given, ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason="no JSON"))
    assert scores["answered"] is False and scores["l2"] is None and scores["gt_in_frame"] is None


def test_the_official_scorer_is_registered_under_its_name():
    from povagent.plugins import build_plugin_host

    scorer = build_plugin_host().create("scorer", "official")
    assert isinstance(scorer, OfficialScorer)

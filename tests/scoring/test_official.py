"""The official metric on the hand-made fixture, against values worked out by hand (1e-9).

Fixture geometry (tests/fixtures/make_povbench_mini.py): house 0's observer camera and frame 0
sit at (0, 1.5, 0), yaw 0, horizon 0, fov 90, so f/W = 0.5 and a camera-space point
(xc, yc, zc) lands at u = 0.5 + 0.5 xc/zc, v = 0.5 - 0.5 yc/zc. Frame 1 looks the other way
(yaw 180). House 1's camera has yaw 45.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from povagent.scoring.normalized_l2 import MAX_L2, UNANSWERED, normalized_l2, score_point, scoring_frame
from povagent.scoring.prediction_summary import summary_of
from povagent.scoring.predictions import score_official_rows

# house 0 GT points (surface-corrected) and their projections
UP = (0.5, 0.5 + 0.5 * 0.7 / 3.0)           # (0, 0.8, 3)
FRONT = (0.5, 0.5 + 0.5 * 1.3 / 1.8)        # (0, 0.2, 1.8)
LEFT = (0.5 - 0.5 * 0.2 / 3.0, UP[1])       # (-0.2, 0.8, 3): on the bed
RIGHT = (0.5 + 0.5 * 1.5 / 3.0, 0.5 + 0.5 * 1.3 / 3.0)  # raw placement (1.5, 0.2, 3)

# house 1, yaw 45: front GT (g, 0.2, g) with g = 2.5 - 0.2/sqrt2
S2 = math.sqrt(2.0)
G = 2.5 - 0.2 / S2
FRONT_B = (0.5, 0.5 + 0.5 * 1.3 / (G * S2))
# left GT (g, 1.0, 3.5 + 0.2/sqrt2): xc = (x - z)/sqrt2, zc = (x + z)/sqrt2, yc = -0.5
LX, LZ = G, 3.5 + 0.2 / S2
LEFT_B = (0.5 + 0.5 * ((LX - LZ) / S2) / ((LX + LZ) / S2), 0.5 + 0.5 * 0.5 / ((LX + LZ) / S2))


def l2(px, py, gu, gv, w=512, h=512):
    return math.hypot(min(max(px / w, 0), 1) - gu, min(max(py / h, 0), 1) - gv)


@pytest.mark.parametrize(
    "iid, expected",
    [
        ("train_house_00000/0/up/c", UP),
        ("train_house_00000/0/front/c", FRONT),
        ("train_house_00000/0/left/c", LEFT),
        ("train_house_00000/0/right/c", RIGHT),
        ("train_house_00001/7/front/c", FRONT_B),
        ("train_house_00001/7/left/c", LEFT_B),
    ],
)
def test_gt_projects_into_the_observer_view_as_worked_out_by_hand(mini_dataset, iid, expected):
    inst = mini_dataset.instance(iid)
    s = score_point(inst, scoring_frame(inst), 256.0, 256.0)
    assert s.gt_u == pytest.approx(expected[0], abs=1e-9)
    assert s.gt_v == pytest.approx(expected[1], abs=1e-9)
    assert s.gt_in_frame
    assert s.l2 == pytest.approx(math.hypot(0.5 - expected[0], 0.5 - expected[1]), abs=1e-9)


def test_inferred_answer_is_scored_in_the_selected_frame(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/left/a")
    s = score_point(inst, scoring_frame(inst, selected_image=0), 100.0, 400.0)
    assert s.l2 == pytest.approx(l2(100, 400, *LEFT), abs=1e-9)


def test_gt_behind_the_selected_frame_sits_at_the_centre_and_is_out_of_frame(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/left/b")
    s = score_point(inst, scoring_frame(inst, selected_image=1), 256.0, 256.0)
    assert (s.gt_u, s.gt_v, s.gt_in_frame, s.gt_behind) == (0.5, 0.5, False, True)
    assert s.l2 == 0.0  # the blind spot, reproduced exactly
    assert s.l2_strict == pytest.approx(MAX_L2)


def test_out_of_range_prediction_is_clamped(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/up/c")
    s = score_point(inst, scoring_frame(inst), 1000.0, -50.0)
    assert s.l2 == pytest.approx(math.hypot(1.0 - UP[0], 0.0 - UP[1]), abs=1e-9)


def test_unknown_selected_frame_is_unanswered(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/up/a")
    assert scoring_frame(inst, selected_image=7) is None
    assert not score_point(inst, None, 1.0, 1.0).answered


@given(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4), st.floats(-5, 5), st.floats(-5, 5))
def test_clamping_bounds_the_error_by_sqrt2(x, y, gu, gv):
    assert 0.0 <= normalized_l2(x, y, 512, 512, gu, gv) <= MAX_L2 + 1e-12


def row(house, pair, direction, cond, x, y, image=None, parse_error=False, points=None):
    return dict(house_id=house, pair_id=pair, direction=direction, type=cond, predicted_x=x,
                predicted_y=y, predicted_image=image, parse_error=parse_error, predicted_points=points)


def test_summary_on_the_fixture_equals_hand_computed_means(mini_dataset):
    rows = [
        row("train_house_00000", 0, "up", "c", 256, 256),                         # C: |centre - UP|
        row("train_house_00000", 0, "front", "c", 0, 511),                         # C
        row("train_house_00000", 0, "left", "a", 100, 400, "exploration_images/frame_000.png"),
        row("train_house_00000", 0, "left", "b", 256, 256, "exploration_images/frame_001.png"),  # blind spot: 0
        row("train_house_00000", 0, "right", "a", 10, 10, None),                   # no frame: unanswered
        row("train_house_00001", "7", "front", "c", None, None, parse_error=True), # unanswered
        row("train_house_00001", "7", "left", "c", 0, 0, points=[[0, 0], [200, 300]]),  # centroid (100, 150)
    ]
    scored, warnings = score_official_rows(rows, mini_dataset)
    assert warnings == []
    s = summary_of(scored)
    e_up = math.hypot(0.5 - UP[0], 0.5 - UP[1])
    e_front = l2(0, 511, *FRONT)
    e_left_a = l2(100, 400, *LEFT)
    e_left_c = l2(100, 150, *LEFT_B)
    overall = [e_up, e_front, e_left_a, 0.0, e_left_c]
    assert s["overall"]["n"] == 5 and s["overall"]["n_total"] == 7
    assert s["overall"]["response_rate"] == pytest.approx(5 / 7, abs=1e-12)
    assert s["overall"]["mean_l2"] == pytest.approx(sum(overall) / 5, abs=1e-9)
    mean = sum(overall) / 5
    assert s["overall"]["std_l2"] == pytest.approx(math.sqrt(sum((e - mean) ** 2 for e in overall) / 5), abs=1e-9)
    assert s["per_condition"]["c"]["mean_l2"] == pytest.approx((e_up + e_front + e_left_c) / 3, abs=1e-9)
    assert s["per_condition"]["c"]["response_rate"] == pytest.approx(3 / 4)
    assert s["per_condition"]["b"]["pct_in_frame"] == 0.0
    assert s["per_direction"]["left"]["mean_l2"] == pytest.approx((e_left_a + 0.0 + e_left_c) / 3, abs=1e-9)
    assert s["per_direction"]["right"]["n"] == 0 and s["per_direction"]["right"]["mean_l2"] is None
    assert s["per_condition_direction"]["a/left"]["mean_l2"] == pytest.approx(e_left_a, abs=1e-9)


def test_multi_point_answers_keep_the_closest_point_error(mini_dataset):
    rows = [row("train_house_00001", "7", "left", "c", 0, 0, points=[[0, 0], [200, 300]])]
    (scored,), _ = score_official_rows(rows, mini_dataset)
    assert scored.l2_closest == pytest.approx(min(l2(0, 0, *LEFT_B), l2(200, 300, *LEFT_B)), abs=1e-9)


def test_rows_for_unknown_instances_are_warned_about(mini_dataset):
    scored, warnings = score_official_rows([row("nohouse", 1, "up", "c", 1, 1)], mini_dataset)
    assert warnings and "nohouse/1/up/c" in warnings[0]
    assert len(scored) == 1 and not scored[0].score.answered


def test_the_centre_guess_error_in_the_scored_frame_is_recorded_beside_the_answer(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/left/a")
    frame = scoring_frame(inst, selected_image=0)
    answer, centre = score_point(inst, frame, 40.0, 470.0), score_point(inst, frame, 256.0, 256.0)
    assert answer.as_dict()["l2_center"] == pytest.approx(centre.l2, abs=1e-12)
    assert answer.l2 != pytest.approx(centre.l2)


def test_the_centre_guess_is_perfect_when_the_gt_is_behind_the_scored_frame(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/left/b")
    behind = score_point(inst, scoring_frame(inst, selected_image=1), 10.0, 10.0)
    assert behind.gt_behind and behind.as_dict()["l2_center"] == 0.0


def test_an_unanswered_row_has_no_centre_guess_error():
    assert UNANSWERED.as_dict()["l2_center"] is None

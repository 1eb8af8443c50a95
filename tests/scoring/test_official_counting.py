"""Counting as the official scorer counts (issue 13, items 5-11 and 13), pinned on the fixture.

Fixture geometry (tests/fixtures/make_povbench_mini.py): house 0's observer camera and its
frame 0 sit at (0, 1.5, 0), yaw 0, horizon 0, fov 90, so f = W/2 and a camera-space point
(xc, yc, zc) lands at u = 0.5 + 0.5 xc/zc, v = 0.5 - 0.5 (W/H) yc/zc. House 0's left GT is
(-0.2, 0.8, 3) (on the bed): xc = -0.2, yc = -0.7, zc = 3.
"""

from __future__ import annotations

import json
import math
import shutil

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.dataset import load_dataset
from povagent.dataset.loader import ground_truth_point
from povagent.dataset.validate import validate_dataset
from povagent.geometry.camera import Camera
from povagent.results.official_format import read_official_run
from povagent.results.prediction_files import score_predictions
from povagent.scoring.breakdown import ScoredRow, breakdown
from povagent.scoring.prediction_summary import summary_of
from povagent.scoring.predictions import score_official_rows

runner = CliRunner()
FRAME0 = "exploration_images/frame_000.png"
LEFT_U = 0.5 - 0.5 * 0.2 / 3.0
LEFT_V_SQUARE = 0.5 + 0.5 * 0.7 / 3.0


def row(house="train_house_00000", pair=0, direction="left", cond="a", x=256.0, y=256.0, image=FRAME0, **extra):
    return {"house_id": house, "pair_id": pair, "direction": direction, "type": cond, "predicted_x": x,
            "predicted_y": y, "predicted_image": image, **extra}


def write(path, doc):
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def l2(px, py, gu, gv):
    clamp = lambda v: min(1.0, max(0.0, v))  # noqa: E731
    return math.hypot(clamp(px) - gu, clamp(py) - gv)


# -- item 5: an official run folder --------------------------------------------------------------


def test_a_run_folder_skips_meta_and_eval_results_the_official_flow_writes_there(tmp_path, mini_dataset):
    write(tmp_path / "predictions.json", {"predictions": [row(), row(direction="up", cond="c")]})
    write(tmp_path / "meta.json", [row()] * 5)
    write(tmp_path / "eval_results.json", {"summary": {}, "evaluations": [row()] * 7})
    summary, warnings = score_predictions(tmp_path, mini_dataset)
    assert summary["overall"]["n_total"] == 2
    assert any("meta.json" in w and "eval_results.json" in w for w in warnings)


def test_unreadable_files_and_objects_without_predictions_are_skipped_with_a_warning(tmp_path, mini_dataset):
    write(tmp_path / "b_predictions.json", [row()])
    (tmp_path / "a_broken.json").write_text('{"predictions": [', encoding="utf-8")
    write(tmp_path / "c_config.json", {"temperature": 0})
    summary, warnings = score_predictions(tmp_path, mini_dataset)
    assert summary["overall"]["n_total"] == 1
    assert any("a_broken.json" in w and "unreadable" in w for w in warnings)
    assert any("c_config.json" in w and "without 'predictions'" in w for w in warnings)


def test_json_lines_files_in_a_folder_are_ignored_as_the_official_loader_ignores_them(tmp_path, mini_dataset):
    write(tmp_path / "p.json", [row()])
    (tmp_path / "more.jsonl").write_text(json.dumps(row()) + "\n", encoding="utf-8")
    summary, warnings = score_predictions(tmp_path, mini_dataset)
    assert summary["overall"]["n_total"] == 1
    assert any("more.jsonl" in w for w in warnings)


def test_a_folder_reads_the_screen_size_from_top_level_keys_a_file_only_from_metadata(tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    doc = {"vlm": "toy", "screen_width": 1024, "screen_height": 256, "predictions": [row()]}
    write(folder / "predictions.json", doc)
    assert read_official_run(folder).screen_size() == (1024.0, 256.0)
    assert read_official_run(folder / "predictions.json").screen_size() == (512.0, 512.0)
    write(folder / "predictions.json", {"metadata": {"screen_width": 300}, "predictions": [row()]})
    assert read_official_run(folder / "predictions.json").screen_size() == (300.0, 512.0)


def test_duplicated_rows_of_merged_house_files_count_again_as_officially(tmp_path, mini_dataset):
    write(tmp_path / "predictions.json", {"predictions": [row()]})
    write(tmp_path / "train_house_00000.json", [row()])  # the merge step's copy of the same row
    summary, _ = score_predictions(tmp_path, mini_dataset)
    assert (summary["overall"]["n"], summary["overall"]["n_total"]) == (2, 2)


# -- item 6: unknown house, pair or placement ----------------------------------------------------


def test_rows_for_unknown_houses_pairs_and_placements_count_as_unanswered_and_are_listed(mini_dataset):
    rows = [
        row(),
        row(house="train_house_09999"),
        row(house="train_house_00001", pair="99", cond="c", image=None),
        row(house="train_house_00001", pair="7", direction="up", cond="c", image=None),  # pair 7 has no up
    ]
    scored, warnings = score_official_rows(rows, mini_dataset)
    s = summary_of(scored)
    assert (s["overall"]["n"], s["overall"]["n_total"]) == (1, 4)
    assert s["overall"]["response_rate"] == pytest.approx(0.25)
    (w,) = [w for w in warnings if "does not have" in w]
    assert "3 row(s)" in w and "train_house_09999" in w and "99" in w and "train_house_00001/7/up/c" in w


# -- item 7: metadata screen size, infinite coordinates ---------------------------------------


def test_metadata_screen_size_divides_ab_pixels_and_shapes_the_selected_frame(tmp_path, mini_dataset):
    write(tmp_path / "p.json", {"metadata": {"screen_width": 1024, "screen_height": 512}, "predictions": [row(x=512.0, y=256.0)]})
    summary, _ = score_predictions(tmp_path / "p.json", mini_dataset)
    gv = 0.5 + 0.5 * (1024 / 512) * 0.7 / 3.0  # f = W/2 = 512 px over a 512-px-high frame
    assert summary["overall"]["mean_l2"] == pytest.approx(math.hypot(0.5 - LEFT_U, 0.5 - gv), abs=1e-12)


def test_metadata_screen_size_does_not_override_the_observer_cameras_own_size(tmp_path, mini_dataset):
    c_row = row(cond="c", image=None, x=512.0, y=256.0)
    write(tmp_path / "p.json", {"metadata": {"screen_width": 1024, "screen_height": 512}, "predictions": [c_row]})
    summary, _ = score_predictions(tmp_path / "p.json", mini_dataset)
    # the observer camera says 512x512: x = 512 is the right edge
    assert summary["overall"]["mean_l2"] == pytest.approx(l2(1.0, 0.5, LEFT_U, LEFT_V_SQUARE), abs=1e-12)


def test_an_infinite_coordinate_is_clamped_to_the_edge(mini_dataset):
    scored, warnings = score_official_rows([row(x=math.inf, y=-math.inf)], mini_dataset)
    assert scored[0].score.answered
    assert scored[0].score.l2 == pytest.approx(l2(1.0, 0.0, LEFT_U, LEFT_V_SQUARE), abs=1e-12)
    assert any("infinite" in w for w in warnings)


def test_a_nan_coordinate_gives_a_nan_mean_as_officially_with_a_warning_naming_the_row(mini_dataset):
    scored, warnings = score_official_rows([row(), row(x=math.nan)], mini_dataset)
    assert math.isnan(summary_of(scored)["overall"]["mean_l2"])
    assert any("NaN" in w and "row 1" in w for w in warnings)


def test_parse_error_does_not_unanswer_a_row_that_has_a_point(mini_dataset):
    scored, _ = score_official_rows([row(parse_error="failed to parse JSON")], mini_dataset)
    assert scored[0].score.answered


def test_several_points_are_clamped_one_by_one_before_the_centroid(mini_dataset):
    pts = [[-512.0, 0.0], [512.0, 0.0]]  # clamped to u = 0 and u = 1: centroid u = 0.5
    (s,), _ = score_official_rows([row(cond="c", image=None, predicted_points=pts)], mini_dataset)
    assert s.score.l2 == pytest.approx(l2(0.5, 0.0, LEFT_U, LEFT_V_SQUARE), abs=1e-12)
    assert s.l2_closest == pytest.approx(min(l2(0, 0, LEFT_U, LEFT_V_SQUARE), l2(1, 0, LEFT_U, LEFT_V_SQUARE)), abs=1e-12)


def test_several_points_are_scored_against_the_gt_clamped_to_the_frame_as_the_single_point_is(mini_dataset):
    # a 1024x128 screen stretches v by W/H = 8: the left GT lands at v = 0.5 + 0.5 * 8 * 0.7 / 3 > 1,
    # out of frame below; the official scorer clamps it to v = 1 before any error, points included
    gt_v = 0.5 + 0.5 * 8.0 * 0.7 / 3.0
    assert gt_v > 1.0
    pts = [[0.0, 0.0], [1024.0, 0.0]]  # u = 0 and u = 1 at v = 0: centroid (0.5, 0)
    (s,), _ = score_official_rows([row(predicted_points=pts)], mini_dataset, screen=(1024.0, 128.0))
    assert s.score.gt_in_frame is False
    assert s.score.l2 == pytest.approx(math.hypot(0.5 - LEFT_U, 0.0 - 1.0), abs=1e-12)
    assert s.l2_closest == pytest.approx(min(math.hypot(0 - LEFT_U, 1.0), math.hypot(1 - LEFT_U, 1.0)), abs=1e-12)


# -- item 8: malformed type and direction -------------------------------------------------------


def test_odd_types_are_their_own_groups_and_every_type_but_c_is_scored_in_the_selected_frame(mini_dataset):
    rows = [row(cond="A"), row(cond=" b"), row(cond="C", image=None), row(cond="C"), row(cond="a")]
    scored, warnings = score_official_rows(rows, mini_dataset)
    s = summary_of(scored)
    assert set(s["per_condition"]) == {"a", "A", " b", "C"}
    assert s["per_condition"]["A"]["n"] == 1 and s["per_condition"]["a"]["n"] == 1
    # "C" is not "c": scored as an A/B answer, so it needs a selected frame
    assert (s["per_condition"]["C"]["n"], s["per_condition"]["C"]["n_total"]) == (1, 2)
    assert s["per_condition"]["C"]["mean_l2"] == pytest.approx(s["per_condition"]["a"]["mean_l2"], abs=1e-15)
    assert any("'A'" in w and "own condition" in w for w in warnings)
    assert any("' b'" in w for w in warnings)


def test_an_odd_direction_names_no_placement_and_counts_unanswered_in_its_own_group(mini_dataset):
    scored, warnings = score_official_rows([row(direction="Front", cond="c", image=None), row()], mini_dataset)
    s = summary_of(scored)
    assert (s["per_direction"]["Front"]["n"], s["per_direction"]["Front"]["n_total"]) == (0, 1)
    assert (s["overall"]["n"], s["overall"]["n_total"]) == (1, 2)
    assert any("'Front'" in w for w in warnings)


def test_the_score_table_shows_an_odd_type_as_written(tmp_path, mini_root):
    write(tmp_path / "p.json", [row(cond="A")])
    result = runner.invoke(app, ["score", "--predictions", str(tmp_path / "p.json"), "--dataset", str(mini_root)])
    assert result.exit_code == 0, result.output
    assert "type 'A'" in result.stdout


# -- items 9-11: ground truth, cameras, duplicates as the release defines them ---------------------


@pytest.fixture()
def bent_root(tmp_path, mini_root):
    """The fixture with house 1's pair 7 repeated (the last: landmark_type SideTable, objectType
    still Sofa) and house 0's frame_000 repeated in the log (the last: turned to yaw 180)."""
    root = tmp_path / "ds"
    shutil.copytree(mini_root, root)
    shutil.rmtree(root / "artifacts" / "train_house_00002")
    f1 = root / "artifacts" / "train_house_00001" / "train_house_00001.json"
    pairs = json.loads(f1.read_text())
    last = json.loads(json.dumps(pairs[0]))
    last["landmark_type"] = "SideTable"
    f1.write_text(json.dumps([pairs[0], last]))
    log_file = root / "artifacts" / "train_house_00000" / "exploration_log.json"
    log = json.loads(log_file.read_text())
    turned = json.loads(json.dumps(log[0]))
    turned["camera"]["cam_yaw"] = 180.0
    log_file.write_text(json.dumps(log + [turned]))
    return root


def test_the_anchor_type_of_the_surface_rules_is_landmark_type(bent_root):
    ds = load_dataset(bent_root)
    pair = ds.houses["train_house_00001"].pairs["7"]
    assert pair.object_landmark.object_type == "Sofa"
    # left of a SideTable whose surface names it: on the anchor's top, 0.2 m from its centre
    s2 = math.sqrt(2.0)
    assert ground_truth_point(pair, "left") == pytest.approx([3.0 - 0.2 / s2, 1.0, 3.0 + 0.2 / s2], abs=1e-12)


def test_a_repeated_pair_id_the_last_entry_wins_and_validate_reports_it(bent_root):
    ds = load_dataset(bent_root)
    assert ds.houses["train_house_00001"].pairs["7"].landmark_type == "SideTable"
    problems = [str(p) for p in validate_dataset(bent_root)]
    assert any("pair_id" in p and "repeats the one at $[0]" in p and "last" in p for p in problems)


def test_a_repeated_image_path_the_last_record_wins_and_validate_reports_it(bent_root):
    ds = load_dataset(bent_root)
    assert ds.houses["train_house_00000"].frames_by_path[FRAME0].camera.yaw == 180.0
    assert ds.instance("train_house_00000/0/left/a").frame_by_path(FRAME0).camera.yaw == 180.0
    # scored in the turned camera: the GT is behind it, at the centre (the blind spot)
    (s,), _ = score_official_rows([row()], ds)
    assert (s.score.gt_behind, s.score.l2) == (True, 0.0)
    problems = [str(p) for p in validate_dataset(bent_root)]
    assert any("exploration_log.json" in p and "repeats the one at $[0]" in p for p in problems)


def test_a_non_square_camera_takes_its_focal_length_from_the_width():
    cam = Camera((0.0, 0.0, 0.0), 0.0, 0.0, 90.0, 640, 480)  # f = 320 px
    u, v, depth = cam.project_point((0.5, 0.3, 2.0))
    assert (u, v, depth) == pytest.approx((0.5 + 320 * 0.25 / 640, 0.5 - 320 * 0.15 / 480, 2.0), abs=1e-12)
    assert cam.project([(0.5, 0.3, 2.0)]).normalized[0] == pytest.approx((u, v), abs=1e-12)
    assert cam.focal_px == pytest.approx(320.0)


# -- item 13: several runs --------------------------------------------------------------------------


def _rows(run, cond, errors, unanswered=0):
    out = [ScoredRow(cond, "left", True, e, True, e, run) for e in errors]
    return out + [ScoredRow(cond, "left", False, None, None, None, run)] * unanswered


def test_several_runs_give_the_plain_mean_of_each_runs_mean_and_the_pooled_mean_labelled():
    rows = _rows(0, "a", [0.1], unanswered=1) + _rows(1, "a", [0.3, 0.3, 0.3])
    b = breakdown(rows)
    assert b["aggregation"] == "mean of per-run means" and b["runs"] == [0, 1]
    assert b["overall"]["mean_l2"] == pytest.approx((0.1 + 0.3) / 2)
    assert b["overall"]["response_rate"] == pytest.approx((0.5 + 1.0) / 2)
    assert (b["overall"]["n"], b["overall"]["n_total"]) == (4, 5)
    assert b["pooled"]["aggregation"] == "pooled"
    assert b["pooled"]["overall"]["mean_l2"] == pytest.approx(1.0 / 4)
    assert b["per_run"]["0"]["mean_l2"] == pytest.approx(0.1)


def test_a_run_without_an_answer_in_a_cell_is_left_out_of_that_cells_mean():
    rows = _rows(0, "a", [0.2]) + _rows(0, "c", [0.4]) + _rows(1, "a", [0.6]) + _rows(1, "c", [], unanswered=2)
    b = breakdown(rows)
    assert b["per_condition"]["c"]["mean_l2"] == pytest.approx(0.4)  # run 1 answered nothing in C
    assert b["per_condition"]["c"]["response_rate"] == pytest.approx(0.5)  # but its rate, 0, counts
    assert b["per_condition"]["c"]["n_runs"] == 2


def test_one_run_is_its_own_summary():
    rows = _rows(3, "a", [0.1, 0.2])
    b = breakdown(rows)
    assert b["runs"] == [3] and "pooled" not in b
    assert b["overall"]["mean_l2"] == pytest.approx(0.15)


def _root(tmp_path, runs):
    root = tmp_path / "eval_results"
    for name, rows in runs.items():
        (root / name).mkdir(parents=True)
        write(root / name / "predictions.json", {"vlm": "toy", "screen_width": 512, "screen_height": 512, "predictions": rows})
    return root


def test_score_on_a_prediction_root_averages_its_run_folders_per_run(tmp_path, mini_dataset):
    r0 = [row(x=0.0, y=0.0), row(x=None, y=None)]
    r1 = [row(x=512.0, y=512.0)] * 3
    root = _root(tmp_path, {"POVBench_toy_0": r0, "POVBench_toy_1": r1, "POVBench_toy_1_vs": r0})
    summary, _ = score_predictions(root, mini_dataset)
    e0, e1 = l2(0, 0, LEFT_U, LEFT_V_SQUARE), l2(1, 1, LEFT_U, LEFT_V_SQUARE)
    assert summary["run_folders"] == ["POVBench_toy_0", "POVBench_toy_1"]  # *_vs is not a run
    assert summary["overall"]["mean_l2"] == pytest.approx((e0 + e1) / 2, abs=1e-12)
    assert summary["overall"]["response_rate"] == pytest.approx((0.5 + 1.0) / 2)
    assert summary["pooled"]["overall"]["mean_l2"] == pytest.approx((e0 + 3 * e1) / 4, abs=1e-12)


def test_score_on_a_root_of_several_models_scores_each_model(tmp_path, mini_dataset):
    root = _root(tmp_path, {"gpt_0": [row()], "gpt_1": [row()], "qwen_0": [row(x=None, y=None)]})
    summary, _ = score_predictions(root, mini_dataset)
    assert set(summary["models"]) == {"gpt", "qwen"}
    assert summary["models"]["gpt"]["runs"] == [0, 1]


def test_score_json_and_table_show_per_run_means_with_the_pooled_mean_labelled(tmp_path, mini_root):
    root = _root(tmp_path, {"toy_0": [row(x=0.0, y=0.0), row(x=None, y=None)], "toy_1": [row(x=512.0, y=512.0)] * 3})
    out = runner.invoke(app, ["score", "--predictions", str(root), "--dataset", str(mini_root), "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    assert doc["aggregation"] == "mean of per-run means" and doc["pooled"]["aggregation"] == "pooled"
    table = runner.invoke(app, ["score", "--predictions", str(root), "--dataset", str(mini_root)])
    assert "pooled" in table.stdout and "per-run means" in table.stdout


def test_export_files_declaring_runs_are_scored_as_runs(tmp_path, mini_dataset):
    write(tmp_path / "run_0.json", {"metadata": {"run": 0}, "predictions": [row(x=0.0, y=0.0), row(x=None, y=None)]})
    write(tmp_path / "run_1.json", {"metadata": {"run": 1}, "predictions": [row(x=512.0, y=512.0)] * 3})
    summary, warnings = score_predictions(tmp_path, mini_dataset)
    assert summary["runs"] == [0, 1]
    assert summary["overall"]["response_rate"] == pytest.approx(0.75)
    assert any("metadata.run" in w for w in warnings)

"""``povagent export --format long-csv``: the official aggregate_runs.py's ``all_runs_long.csv``.

The official script writes one line per (model, run, item) under a fixed header, from the
official evaluation's per-item record; notebooks read its columns by name and its values as
text. Each test pins one rule of that file.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.cli import app
from povagent.dataset.instances import row_key
from povagent.errors import PredictionsError
from povagent.report.export import LONG_CSV_COLUMNS, export_long_csv
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, ResultsWriter, RowStatus, read_rows
from povagent.scoring.normalized_l2 import project_ground_truth

#: The header of the official all_runs_long.csv, as aggregate_runs.py writes it.
OFFICIAL_HEADER = (
    "model,run_id,eval_dir,pair_id,house_id,direction,type,sentence,status,parse_error,"
    "predicted_x,predicted_y,predicted_x_norm,predicted_y_norm,gt_x,gt_y,gt_in_frame,"
    "error_x,error_y,error_l2,error_l2_min,error_l2_mean,n_points,predicted_image,camera_image,raw_response"
)

A_ID = "train_house_00000/0/right/a"
C_ID = "train_house_00000/0/right/c"


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def make_row(instance, run: int = 0, **fields) -> ResultRow:
    base = dict(
        key=row_key(instance.id, run), instance_id=instance.id, house_id=instance.house_id, pair_id=instance.pair_id,
        direction=str(instance.direction), condition=str(instance.condition), run=run, sentence=instance.sentence,
        backend="mock", strategy="basic", parser=fields.pop("parser", "json"),
    )  # fmt: skip
    return ResultRow(**(base | fields))


def answered(instance, x: float, y: float, k: int | None = None, points=None, raw: str = '{"x": 1}', run: int = 0) -> ResultRow:
    parse = ParsedAnswer(status=ParseStatus.OK, selected_image=k, x=x, y=y, points=points)
    image = instance.frames[k].image_path if k is not None else None
    return make_row(
        instance, run, status=RowStatus.ANSWERED, parse=parse, exchanges=[ExchangeRecord(request_hash="r", raw=raw)],
        prediction=Prediction(selected_image=k, image_path=image, x=x, y=y),
    )  # fmt: skip


@pytest.fixture
def write_rows(tmp_path, mini_root):
    """``write_rows(rows, model=...) -> run folder`` on the hand-made release."""

    def write(rows: list[ResultRow], name: str = "run", model: str = "mock-a") -> Path:
        folder = tmp_path / name
        folder.mkdir()
        config = {"dataset": {"path": str(mini_root)}, "backend": {"name": "mock", "options": {"model": model}}}
        (folder / "config.yaml").write_text(yaml.safe_dump(config))
        with ResultsWriter(folder / "results.jsonl") as w:
            for r in rows:
                w.write(r)
        return folder

    return write


def export_one(folder: Path, **kw) -> dict[str, str]:
    (line,) = read_csv(export_long_csv(folder, **kw))
    return line


# -- the file -----------------------------------------------------------------------------------
def test_the_header_is_the_official_one_in_its_order(run_dir, tmp_path):
    path = export_long_csv(run_dir, tmp_path / "long.csv")
    # the csv module's default dialect, as the official script writes it: CRLF line ends
    assert path.read_bytes().decode("utf-8").split("\r\n", 1)[0] == OFFICIAL_HEADER
    assert ",".join(LONG_CSV_COLUMNS) == OFFICIAL_HEADER


def test_one_line_per_model_run_and_item_with_runs_numbered_from_one(run_dir, mini_dataset):
    lines = read_csv(export_long_csv(run_dir))
    assert (run_dir / "all_runs_long.csv").is_file()
    assert len(lines) == 2 * len(mini_dataset.instances())
    assert {line["run_id"] for line in lines} == {"1", "2"} and {line["model"] for line in lines} == {"mock-a"}
    assert {line["eval_dir"] for line in lines} == {str(run_dir)}
    keys = {(line["run_id"], line["house_id"], line["pair_id"], line["direction"], line["type"]) for line in lines}
    assert len(keys) == len(lines)


def test_items_follow_the_official_runners_order(run_dir):
    lines = [line for line in read_csv(export_long_csv(run_dir)) if line["run_id"] == "1"]
    pair0 = [(line["direction"], line["type"]) for line in lines if line["house_id"] == "train_house_00000"]
    # directions alphabetically, then a, b, c within each
    assert pair0[:6] == [("front", "a"), ("front", "b"), ("front", "c"), ("left", "a"), ("left", "b"), ("left", "c")]
    assert [line["house_id"] for line in lines] == sorted(line["house_id"] for line in lines)


def test_ok_lines_carry_the_official_scorers_error_for_each_row(run_dir):
    ours = {(r.run + 1, r.instance_id): r.scores["official"] for r in read_rows(run_dir / "results.jsonl")}
    n_ok = 0
    for line in read_csv(export_long_csv(run_dir)):
        iid = "/".join((line["house_id"], line["pair_id"], line["direction"], line["type"]))
        score = ours[(int(line["run_id"]), iid)]
        assert (line["status"] == "ok") is score["answered"]
        if line["status"] == "ok":
            n_ok += 1
            assert float(line["error_l2"]) == pytest.approx(score["l2"], abs=1e-15)
            assert line["gt_in_frame"] == str(score["gt_in_frame"])
    assert n_ok > 20


# -- the values of one item ------------------------------------------------------------------------
def test_an_answered_inferred_item_is_evaluated_in_its_selected_frame(write_rows, mini_dataset):
    inst = mini_dataset.instance(A_ID)
    line = export_one(write_rows([answered(inst, 300.0, 100.5, k=1, raw='{"selected_image": 1, "x": 300, "y": 100.5}')]))
    frame = inst.frames[1]
    gt = project_ground_truth(inst.target, frame.camera)
    gx, gy = min(1.0, max(0.0, gt.u)), min(1.0, max(0.0, gt.v))
    px, py = 300.0 / 512, 100.5 / 512
    assert line["status"] == "ok" and line["parse_error"] == ""
    # numbers are written as Python prints floats (the csv module's str())
    assert line["predicted_x"] == "300.0" and line["predicted_y"] == "100.5"
    assert line["predicted_x_norm"] == repr(px) and line["predicted_y_norm"] == repr(py)
    assert line["gt_x"] == repr(gx) and line["gt_y"] == repr(gy) and line["gt_in_frame"] == str(gt.in_frame)
    assert line["error_x"] == repr(px - gx) and line["error_y"] == repr(py - gy)
    assert line["error_l2"] == repr(math.sqrt((px - gx) ** 2 + (py - gy) ** 2))
    assert line["predicted_image"] == line["camera_image"] == frame.image_path
    assert line["error_l2_min"] == line["error_l2_mean"] == line["n_points"] == ""
    assert line["raw_response"] == '{"selected_image": 1, "x": 300, "y": 100.5}'
    assert line["sentence"] == inst.sentence and line["type"] == "a" and line["pair_id"] == "0"


def test_a_given_item_names_the_observer_view_and_no_selected_image(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    line = export_one(write_rows([answered(inst, 256.0, 256.0)]))
    assert line["status"] == "ok" and line["predicted_image"] == ""
    assert line["camera_image"] == inst.frames[0].image_path == "img_from_observer/pair_0.png"


def test_a_prediction_outside_the_frame_is_clamped_to_its_edge(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    line = export_one(write_rows([answered(inst, 900.0, -40.0)]))
    assert line["predicted_x"] == "900.0" and line["predicted_x_norm"] == "1.0" and line["predicted_y_norm"] == "0.0"


def test_an_unparseable_answer_is_no_prediction_with_the_official_parse_error(write_rows, mini_dataset):
    inst = mini_dataset.instance(A_ID)
    parse = ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason="no JSON")
    row = make_row(inst, status=RowStatus.PARSE_ERROR, parse=parse, exchanges=[ExchangeRecord(request_hash="r", raw="I cannot tell.")])
    line = export_one(write_rows([row]))
    assert line["status"] == "no_prediction" and line["parse_error"] == "failed to parse JSON"
    assert line["raw_response"] == "I cannot tell."
    for column in ("predicted_x", "predicted_x_norm", "gt_x", "gt_in_frame", "error_l2", "predicted_image", "camera_image"):
        assert line[column] == "", column


def test_a_failed_request_records_its_error_and_no_response(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    row = make_row(inst, status=RowStatus.INFRA_ERROR, error_type="RateLimitError", error_message="429 Too Many Requests")
    line = export_one(write_rows([row]))
    assert line["status"] == "no_prediction" and line["parse_error"] == "429 Too Many Requests" and line["raw_response"] == ""


def test_a_point_without_a_usable_frame_is_no_selected_image(write_rows, mini_dataset):
    inst = mini_dataset.instance(A_ID)
    # the answer named frame 7 of 3: its point was read, its frame maps to no image
    parse = ParsedAnswer(status=ParseStatus.OUT_OF_RANGE, selected_image=7, x=10.0, y=20.0)
    row = make_row(
        inst, status=RowStatus.ANSWERED, parse=parse, exchanges=[ExchangeRecord(request_hash="r", raw="{}")],
        prediction=Prediction(selected_image=7, x=10.0, y=20.0),
    )  # fmt: skip
    line = export_one(write_rows([row]))
    assert line["status"] == "no_selected_image" and line["parse_error"] == ""
    assert line["predicted_x"] == "10.0" and line["predicted_image"] == "" and line["gt_x"] == ""


def test_a_frame_missing_from_the_exploration_log_is_image_not_in_log(write_rows, mini_dataset):
    inst = mini_dataset.instance(A_ID)
    row = answered(inst, 10.0, 20.0, k=0)
    row.prediction.image_path = "exploration_images/frame_099.png"
    line = export_one(write_rows([row]))
    assert line["status"] == "image_not_in_log"
    assert line["predicted_image"] == "exploration_images/frame_099.png" and line["camera_image"] == ""


def test_rows_of_unknown_pairs_and_directions_keep_their_official_status(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    unknown_pair = answered(inst, 1.0, 2.0)
    unknown_pair.pair_id, unknown_pair.instance_id = "99", "train_house_00000/99/right/c"
    no_placement = answered(inst, 1.0, 2.0)
    no_placement.direction, no_placement.instance_id = "behind", "train_house_00000/0/behind/c"
    for r in (unknown_pair, no_placement):
        r.key = row_key(r.instance_id, 0)
    lines = read_csv(export_long_csv(write_rows([unknown_pair, no_placement])))
    assert {line["pair_id"]: line["status"] for line in lines} == {"99": "entry_not_found", "0": "placement_not_found"}


def test_several_points_score_their_clamped_centroid_and_keep_the_closest(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    gt = project_ground_truth(inst.target, inst.frames[0].camera)
    gx, gy = min(1.0, max(0.0, gt.u)), min(1.0, max(0.0, gt.v))
    # one point far outside the frame: clamping it before averaging moves the centroid
    points = [(gt.u * 512, gt.v * 512), (5000.0, gt.v * 512)]
    row = answered(inst, (points[0][0] + 5000.0) / 2, gt.v * 512, points=points)
    line = export_one(write_rows([row]))
    clamped = [(min(1.0, max(0.0, x / 512)), min(1.0, max(0.0, y / 512))) for x, y in points]
    cx, cy = (clamped[0][0] + clamped[1][0]) / 2, (clamped[0][1] + clamped[1][1]) / 2
    assert line["n_points"] == "2"
    assert line["error_l2_mean"] == line["error_l2"] == repr(math.hypot(cx - gx, cy - gy))
    assert line["error_l2_min"] == repr(min(math.hypot(a - gx, b - gy) for a, b in clamped))


# -- runs, models, sweeps -----------------------------------------------------------------------------
def test_a_sweep_writes_every_cell_labelled_by_its_system_sorted_by_model_then_run(sweep_dir):
    lines = read_csv(export_long_csv(sweep_dir))
    models = [line["model"] for line in lines]
    assert sorted(set(models)) == ["mock-a · basic", "mock-a · cot", "mock-b · basic", "mock-b · cot"]
    assert models == sorted(models) and len(lines) == 4 * 18
    assert len({line["eval_dir"] for line in lines}) == 4


def test_one_run_index_and_a_model_label_can_be_chosen(run_dir, tmp_path):
    lines = read_csv(export_long_csv(run_dir, tmp_path / "x.csv", run=1, model="qwen"))
    assert {line["run_id"] for line in lines} == {"2"} and {line["model"] for line in lines} == {"qwen"}


def test_a_model_label_for_a_whole_sweep_is_refused(sweep_dir, tmp_path):
    with pytest.raises(PredictionsError, match="--model labels one run folder"):
        export_long_csv(sweep_dir, tmp_path / "x.csv", model="qwen")


def test_a_run_without_a_loadable_dataset_asks_for_one(run_dir, tmp_path):
    with pytest.raises(PredictionsError, match="pass --dataset"):
        export_long_csv(run_dir, tmp_path / "x.csv", dataset_path=tmp_path / "missing")


def test_the_command_writes_the_long_csv(run_dir, tmp_path):
    out = tmp_path / "all.csv"
    result = CliRunner().invoke(app, ["export", str(run_dir), "--format", "long-csv", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.output and len(read_csv(out)) == 36


def test_a_point_list_records_its_first_point_as_the_prediction(write_rows, mini_dataset):
    """The official runner wrote RoboPoint's first point as predicted_x/y (and so the normalized
    prediction and error_x/y are that point's); only error_l2 is the centroid's."""
    inst = mini_dataset.instance(C_ID)
    gt = project_ground_truth(inst.target, inst.frames[0].camera)
    gx, gy = min(1.0, max(0.0, gt.u)), min(1.0, max(0.0, gt.v))
    points = [(100.0, 200.0), (300.0, 400.0)]
    row = answered(inst, 200.0, 300.0, points=points)  # the parse's prediction: the centroid
    line = export_one(write_rows([row]))
    assert (line["predicted_x"], line["predicted_y"]) == ("100.0", "200.0")
    assert (line["predicted_x_norm"], line["predicted_y_norm"]) == (repr(100.0 / 512), repr(200.0 / 512))
    assert (line["error_x"], line["error_y"]) == (repr(100.0 / 512 - gx), repr(200.0 / 512 - gy))
    centroid = math.hypot((100.0 + 300.0) / 2 / 512 - gx, (200.0 + 400.0) / 2 / 512 - gy)
    assert line["error_l2"] == line["error_l2_mean"] == repr(centroid)


def test_an_unreadable_robopoint_answer_records_the_runners_points_failure(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    parse = ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason="no tuple")
    exchanges = [ExchangeRecord(request_hash="r", raw="somewhere left")]
    rows = [
        make_row(inst, status=RowStatus.PARSE_ERROR, parse=parse, exchanges=exchanges, parser=name, run=k)
        for k, name in enumerate(["robopoint-official", "robopoint", "official"])
    ]
    lines = read_csv(export_long_csv(write_rows(rows)))
    assert [line["parse_error"] for line in lines] == ["failed to parse points", "failed to parse points", "failed to parse JSON"]


# -- formulas ------------------------------------------------------------------------------------
@pytest.mark.parametrize("raw", ["=HYPERLINK(\"http://x\",\"y\")", "+1+cmd|' /C calc'!A0", "-2+3", "@SUM(A1:A9)", "\t=1+1", "\r=1+1"])
def test_an_answer_a_spreadsheet_would_run_is_written_after_a_single_quote(write_rows, mini_dataset, raw):
    inst = mini_dataset.instance(C_ID)
    line = export_one(write_rows([answered(inst, 256.0, 256.0, raw=raw)]))
    assert line["raw_response"] == "'" + raw


def test_negative_numbers_and_plain_answers_are_written_as_they_are(write_rows, mini_dataset):
    inst = mini_dataset.instance(C_ID)
    # a point left of and above the ground truth: the signed errors are negative numbers
    line = export_one(write_rows([answered(inst, 0.0, 0.0, raw="-0.5")]))
    assert line["error_x"].startswith("-") and float(line["error_x"]) < 0 and float(line["error_y"]) < 0
    assert line["raw_response"] == "-0.5"  # text that is a plain number is no formula

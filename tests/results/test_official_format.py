"""Reading and writing official POVBench prediction files (povagent/results/official_format.py)."""

from __future__ import annotations

import json

import pytest

from povagent.dataset.release_models import Condition, Direction
from povagent.errors import PredictionsError
from povagent.results.official_format import (
    OfficialPrediction,
    read_official_predictions,
    write_official_predictions,
)

ROW_A = {
    "house_id": "train_house_00000",
    "pair_id": 3,
    "direction": "left",
    "type": "a",
    "sentence": "to the left of the sofa",
    "predicted_x": 100.5,
    "predicted_y": 200,
    "predicted_image": "exploration_images/frame_001.png",
    "parse_error": False,
    "candidate_images": ["exploration_images/frame_000.png"],
}
ROW_C = {
    "house_id": "train_house_00001",
    "pair_id": "7",
    "direction": "up",
    "type": "C",
    "predicted_x": None,
    "predicted_y": None,
    "parse_error": "no JSON object",
}


def _write(path, doc):
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def test_reads_a_bare_list_of_rows(tmp_path):
    rows = read_official_predictions(_write(tmp_path / "p.json", [ROW_A, ROW_C]))
    assert [r.instance_id for r in rows] == [
        "train_house_00000/3/left/a",
        "train_house_00001/7/up/c",
    ]
    assert rows[0].predicted_x == 100.5 and rows[0].predicted_image == "exploration_images/frame_001.png"
    assert rows[1].type is Condition.GIVEN and rows[1].direction is Direction.UP


def test_reads_metadata_and_predictions_object(tmp_path):
    f = _write(tmp_path / "p.json", {"metadata": {"model": "gpt"}, "predictions": [ROW_A]})
    assert len(read_official_predictions(f)) == 1


def test_reads_every_file_of_a_folder_in_name_order(tmp_path):
    _write(tmp_path / "b.json", [ROW_C])
    _write(tmp_path / "a.json", {"metadata": {}, "predictions": [ROW_A]})
    (tmp_path / "notes.txt").write_text("ignored")
    rows = read_official_predictions(tmp_path)
    assert [r.house_id for r in rows] == ["train_house_00000", "train_house_00001"]


def test_reads_json_lines(tmp_path):
    f = tmp_path / "p.jsonl"
    f.write_text(json.dumps(ROW_A) + "\n\n" + json.dumps(ROW_C) + "\n")
    assert len(read_official_predictions(f)) == 2


def test_keeps_extra_keys(tmp_path):
    rows = read_official_predictions(_write(tmp_path / "p.json", [dict(ROW_A, model_name="x", raw="...")]))
    assert rows[0].model_extra == {"model_name": "x", "raw": "..."}


def test_missing_coordinates_mean_no_point(tmp_path):
    rows = read_official_predictions(_write(tmp_path / "p.json", [ROW_C, dict(ROW_A, predicted_x="")]))
    assert not rows[0].has_point and not rows[1].has_point


def test_bad_row_names_file_and_row_index(tmp_path):
    f = _write(tmp_path / "p.json", {"predictions": [ROW_A, dict(ROW_A, predicted_x="abc")]})
    with pytest.raises(PredictionsError) as err:
        read_official_predictions(f)
    msg = str(err.value)
    assert "p.json" in msg and "row 1" in msg and "predicted_x" in msg


def test_unknown_direction_is_rejected(tmp_path):
    f = _write(tmp_path / "p.json", [dict(ROW_A, direction="behind")])
    with pytest.raises(PredictionsError, match=r"row 0.*direction"):
        read_official_predictions(f)


def test_row_that_is_not_an_object_is_rejected(tmp_path):
    with pytest.raises(PredictionsError, match="row 0: expected an object"):
        read_official_predictions(_write(tmp_path / "p.json", ["oops"]))


def test_invalid_json_names_the_file(tmp_path):
    f = tmp_path / "p.json"
    f.write_text("[{")
    with pytest.raises(PredictionsError, match=r"p\.json: invalid JSON"):
        read_official_predictions(f)


def test_wrong_top_level_shape_is_rejected(tmp_path):
    with pytest.raises(PredictionsError, match="expected a list"):
        read_official_predictions(_write(tmp_path / "p.json", {"rows": []}))


def test_missing_path_is_a_predictions_error(tmp_path):
    with pytest.raises(PredictionsError, match="no such predictions file"):
        read_official_predictions(tmp_path / "nope.json")


def test_empty_folder_is_a_predictions_error(tmp_path):
    with pytest.raises(PredictionsError, match="no predictions files"):
        read_official_predictions(tmp_path)


def test_write_then_read_round_trips(tmp_path):
    rows = [OfficialPrediction.model_validate(ROW_A), OfficialPrediction.model_validate(ROW_C)]
    out = write_official_predictions(tmp_path / "out" / "preds.json", rows, {"model": "m"})
    again = read_official_predictions(out)
    assert again == rows
    assert json.loads(out.read_text())["metadata"] == {"model": "m"}

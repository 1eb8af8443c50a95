"""The official per-item evaluation record of a result row (what eval_results.json holds per item)."""

from __future__ import annotations

import math

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.instances import row_key
from povagent.results.evaluations import official_evaluation, raw_response
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, RowStatus
from povagent.scoring.normalized_l2 import clamp_unit

C_ID = "train_house_00000/0/right/c"
A_ID = "train_house_00000/0/right/a"


def row_of(instance, **fields) -> ResultRow:
    base = dict(
        key=row_key(instance.id, 0), instance_id=instance.id, house_id=instance.house_id, pair_id=instance.pair_id,
        direction=str(instance.direction), condition=str(instance.condition), sentence=instance.sentence,
    )  # fmt: skip
    return ResultRow(**(base | fields))


def answered_c(instance, x: float, y: float) -> ResultRow:
    parse = ParsedAnswer(status=ParseStatus.OK, x=x, y=y)
    return row_of(instance, status=RowStatus.ANSWERED, parse=parse, prediction=Prediction(x=x, y=y))


def test_clamping_keeps_nan_and_sends_infinities_to_the_edges():
    assert math.isnan(clamp_unit(float("nan")))
    assert clamp_unit(float("inf")) == 1.0 and clamp_unit(float("-inf")) == 0.0 and clamp_unit(0.25) == 0.25


def test_a_nan_coordinate_is_scored_and_its_error_is_nan(mini_dataset):
    # the official scorer keeps a NaN answer as answered: its error, and so its mean, is NaN
    record = official_evaluation(answered_c(mini_dataset.instance(C_ID), float("nan"), 100.0), mini_dataset)
    assert record["status"] == "ok" and math.isnan(record["predicted_x_norm"]) and math.isnan(record["error_l2"])


def test_an_infinite_coordinate_is_clamped_to_the_image_edge(mini_dataset):
    record = official_evaluation(answered_c(mini_dataset.instance(C_ID), float("inf"), 100.0), mini_dataset)
    assert record["status"] == "ok" and record["predicted_x_norm"] == 1.0 and math.isfinite(record["error_l2"])


def test_a_missing_prediction_is_reported_before_an_unknown_pair(mini_dataset):
    inst = mini_dataset.instance(C_ID)
    row = row_of(inst, status=RowStatus.PARSE_ERROR, parse=ParsedAnswer(status=ParseStatus.UNPARSEABLE))
    row.pair_id, row.instance_id = "99", "train_house_00000/99/right/c"
    assert official_evaluation(row, mini_dataset)["status"] == "no_prediction"


def test_an_unanswered_row_with_a_point_but_no_frame_keeps_the_point(mini_dataset):
    inst = mini_dataset.instance(A_ID)
    parse = ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason="frame missing", x=3.0, y=4.0)
    record = official_evaluation(row_of(inst, status=RowStatus.PARSE_ERROR, parse=parse), mini_dataset)
    assert record["status"] == "no_selected_image" and record["predicted_x"] == 3.0 and record["parse_error"] is None


def test_a_given_row_with_a_point_but_no_answer_is_no_prediction(mini_dataset):
    # Given has no frame to miss: a parse that did not answer is the official parse failure
    inst = mini_dataset.instance(C_ID)
    parse = ParsedAnswer(status=ParseStatus.UNPARSEABLE, x=3.0, y=4.0)
    record = official_evaluation(row_of(inst, status=RowStatus.PARSE_ERROR, parse=parse), mini_dataset)
    assert record["status"] == "no_prediction" and record["parse_error"] == "failed to parse JSON"


def test_the_raw_response_is_the_last_answer_of_a_multi_turn_row(mini_dataset):
    inst = mini_dataset.instance(C_ID)
    exchanges = [ExchangeRecord(request_hash="1", raw="first"), ExchangeRecord(request_hash="2", raw="final"), ExchangeRecord(request_hash="3")]
    assert raw_response(row_of(inst, status=RowStatus.ANSWERED, exchanges=exchanges)) == "final"
    assert raw_response(row_of(inst, status=RowStatus.INFRA_ERROR)) == ""

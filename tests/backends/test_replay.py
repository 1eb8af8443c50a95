"""The replay backend (plugins/backends/replay.py): answers from a run folder's results or
from an official predictions file, on the hand-made dataset with the real basic strategy."""

from __future__ import annotations

import asyncio
import json

import pytest

from povagent.errors import PredictionsError
from povagent.exchange.images import ImageStore
from povagent.interfaces import PermanentBackendError
from povagent.plugins import get_plugin_host
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus
from povagent_plugins.backends.replay import ReplayBackend
from povagent_plugins.strategies.basic import BasicStrategy

pytestmark = pytest.mark.timeout(30)


@pytest.fixture(scope="module")
def requests_(mini_dataset):
    store = ImageStore()
    return {i.id: BasicStrategy().build(i, store) for i in mini_dataset.instances()}


A_ID = "train_house_00000/0/right/a"
C_ID = "train_house_00001/7/left/c"


def row(instance_id: str, raw: str | None, status: RowStatus = RowStatus.ANSWERED, run: int = 0) -> ResultRow:
    house, pair, direction, condition = instance_id.split("/")
    return ResultRow(
        key=f"{instance_id}#{run}",
        instance_id=instance_id,
        house_id=house,
        pair_id=pair,
        direction=direction,
        condition=condition,
        run=run,
        status=status,
        exchanges=[ExchangeRecord(request_hash="h", raw=raw)] if raw is not None else [],
        error_message=None if raw is not None else "HTTP 401",
    )


def write_results(folder, rows):
    with ResultsWriter(folder / "results.jsonl") as w:
        for r in rows:
            w.write(r)
    return folder


def answer(backend, request) -> str:
    return asyncio.run(backend.complete(request, ImageStore())).text


def official_row(instance_id, **fields):
    house, pair, direction, condition = instance_id.split("/")
    return {"house_id": house, "pair_id": pair, "direction": direction, "type": condition, **fields}


# -- our results ---------------------------------------------------------------------------------
def test_replays_the_recorded_raw_answer_from_a_run_folder(tmp_path, requests_):
    write_results(tmp_path, [row(A_ID, "I think {\"selected_image\": 2, \"x\": 5, \"y\": 6}")])
    assert answer(ReplayBackend(str(tmp_path)), requests_[A_ID]) == 'I think {"selected_image": 2, "x": 5, "y": 6}'


def test_replays_from_a_results_file_path(tmp_path, requests_):
    write_results(tmp_path, [row(C_ID, '{"x": 1, "y": 2}')])
    assert answer(ReplayBackend(str(tmp_path / "results.jsonl")), requests_[C_ID]) == '{"x": 1, "y": 2}'


def test_missing_row_is_a_permanent_error_naming_the_key(tmp_path, requests_):
    write_results(tmp_path, [row(C_ID, '{"x": 1, "y": 2}')])
    with pytest.raises(PermanentBackendError, match=f"no recorded answer for {A_ID}#0"):
        answer(ReplayBackend(str(tmp_path)), requests_[A_ID])


def test_row_without_an_answer_is_a_permanent_error_saying_why(tmp_path, requests_):
    write_results(tmp_path, [row(A_ID, None, RowStatus.INFRA_ERROR)])
    with pytest.raises(PermanentBackendError, match="infra_error"):
        answer(ReplayBackend(str(tmp_path)), requests_[A_ID])


def test_last_row_of_a_repeated_key_wins(tmp_path, requests_):
    write_results(tmp_path, [row(C_ID, "old"), row(C_ID, "new")])
    assert answer(ReplayBackend(str(tmp_path)), requests_[C_ID]) == "new"


# -- official predictions ------------------------------------------------------------------------
def test_official_row_maps_predicted_image_to_the_frame_index(tmp_path, requests_):
    frame = requests_[A_ID].instance.frames[2]
    f = tmp_path / "preds.json"
    f.write_text(json.dumps([official_row(A_ID, predicted_x=12.5, predicted_y=40, predicted_image=frame.image_path)]))
    assert json.loads(answer(ReplayBackend(str(f)), requests_[A_ID])) == {"selected_image": 2, "x": 12.5, "y": 40}


def test_official_c_row_answers_a_point(tmp_path, requests_):
    f = tmp_path / "preds.json"
    f.write_text(json.dumps({"metadata": {}, "predictions": [official_row(C_ID, predicted_x=3, predicted_y=4)]}))
    assert json.loads(answer(ReplayBackend(str(f)), requests_[C_ID])) == {"x": 3, "y": 4}


def test_official_row_without_a_point_is_a_non_response(tmp_path, requests_):
    f = tmp_path / "preds.json"
    f.write_text(json.dumps([official_row(C_ID, predicted_x=None, predicted_y=None, parse_error=True)]))
    assert answer(ReplayBackend(str(f)), requests_[C_ID]) == ""


def test_official_row_with_an_unknown_frame_scores_unanswered(tmp_path, requests_, mini_dataset):
    f = tmp_path / "preds.json"
    f.write_text(json.dumps([official_row(A_ID, predicted_x=1, predicted_y=2, predicted_image="nope.png")]))
    host = get_plugin_host()
    request = requests_[A_ID]
    parsed = host.create("parser", "json").parse(answer(ReplayBackend(str(f)), request), request.answer)
    assert host.create("scorer", "official").score(request.instance, parsed, mini_dataset)["answered"] is False


def test_official_folder_is_read_whole(tmp_path, requests_):
    (tmp_path / "a.json").write_text(json.dumps([official_row(C_ID, predicted_x=3, predicted_y=4)]))
    (tmp_path / "b.json").write_text(json.dumps([official_row(A_ID, predicted_x=5, predicted_y=6)]))
    backend = ReplayBackend(str(tmp_path))
    assert len(backend) == 2 and json.loads(answer(backend, requests_[C_ID])) == {"x": 3, "y": 4}


def test_bad_official_file_fails_when_the_backend_is_made(tmp_path):
    f = tmp_path / "preds.json"
    f.write_text(json.dumps([{"house_id": "h"}]))
    with pytest.raises(PredictionsError, match=r"preds.json: row 0"):
        ReplayBackend(str(f))


def test_missing_path_is_a_predictions_error(tmp_path):
    with pytest.raises(PredictionsError, match="does not exist"):
        ReplayBackend(str(tmp_path / "nope"))


def test_replay_is_registered_and_not_cached():
    assert "replay" in get_plugin_host().names("backend") and ReplayBackend.cacheable is False

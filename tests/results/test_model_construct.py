"""construct: the object pydantic's model_construct makes, built directly."""

from __future__ import annotations

from pydantic import BaseModel, Field

from povagent.answers.spec import ParsedAnswer
from povagent.results.model_construct import construct
from povagent.results.rows import ROW_FORMAT, ExchangeRecord, OfficialReading, Prediction, ResultRow, RowStatus


def _state(model: BaseModel) -> tuple:
    return (type(model), model.__dict__, list(model.__dict__), model.model_fields_set, model.__pydantic_extra__,
            model.__pydantic_private__, model.model_dump_json())  # fmt: skip


def _row_fields() -> dict:
    return dict(
        format_version=ROW_FORMAT, key="set/1#0", instance_id="set/1", house_id="set", pair_id="1", direction="", condition="", run=0, sentence="Where?",
        backend="random", model="random", profile=None, strategy="choice", parser="choice", label=None, config_hash="abc",
        status=RowStatus.ANSWERED, exchanges=[ExchangeRecord(request_hash="h", raw="A")], parse=ParsedAnswer(status="ok", choice="A"),
        prediction=Prediction(answer_type="choice", value={"choice": "A"}), scores={"choice": {"answered": True, "correct": False}},
        error_type=None, error_message=None, latency_s=0.25, prompt_tokens=3, completion_tokens=1, cost_usd=0.0, retries=0,
        started_at="2026-01-01T00:00:00.000+00:00", finished_at="2026-01-01T00:00:00.250+00:00",
        official_reading=OfficialReading(parser="official", parse=ParsedAnswer(status="unparseable", reason="no JSON")),
        category="Camera", main_category=None,
    )  # fmt: skip


def test_a_row_naming_every_field_is_the_object_model_construct_makes():
    fields = _row_fields()
    assert set(fields) == set(ResultRow.model_fields)  # every field named: the direct path
    assert _state(construct(ResultRow, **fields)) == _state(ResultRow.model_construct(**fields))


def test_fields_in_another_order_are_kept_in_the_declared_order():
    fields = dict(reversed(list(_row_fields().items())))
    made = construct(ResultRow, **fields)
    assert list(made.__dict__) == list(ResultRow.model_fields)
    assert _state(made) == _state(ResultRow.model_construct(**fields))


def test_a_row_leaving_fields_to_their_defaults_is_model_construct_s():
    fields = {k: v for k, v in _row_fields().items() if k not in ("label", "category")}
    assert _state(construct(ResultRow, **fields)) == _state(ResultRow.model_construct(**fields))


def test_an_exchange_and_a_prediction_are_model_construct_s():
    exchange = dict(request_hash="h", image_hashes=["i"], prompt="--- user ---\nQ", prompt_continues=False, raw="A", latency_s=0.1,
                    prompt_tokens=None, completion_tokens=None, cost_usd=None, retries=0, cached=False)  # fmt: skip
    assert _state(construct(ExchangeRecord, **exchange)) == _state(ExchangeRecord.model_construct(**exchange))
    prediction = dict(selected_image=None, image_path=None, x=None, y=None, answer_type="choice", value={"choice": "B"})
    assert _state(construct(Prediction, **prediction)) == _state(Prediction.model_construct(**prediction))


def test_a_model_with_an_alias_is_left_to_model_construct():
    class Aliased(BaseModel):
        name: str = Field(alias="title")
        n: int = 0

    made = construct(Aliased, title="x", n=1)
    assert made.name == "x" and _state(made) == _state(Aliased.model_construct(title="x", n=1))

"""The CoT and Spatial-CoT strategies (plugins/strategies/cot.py)."""

from __future__ import annotations

from povagent.dataset.models import Condition
from povagent.exchange.images import ImageStore
from povagent.exchange.prompts import load_template
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.cot import CotStrategy, SpatialCotStrategy


def test_cot_strategies_allow_1024_new_tokens(make_instance, facing_z):
    inst = make_instance([facing_z()])
    assert CotStrategy().build(inst, ImageStore()).generation.max_tokens == 1024
    assert SpatialCotStrategy().build(inst, ImageStore()).generation.max_tokens == 1024


def test_cot_token_budget_is_configurable(make_instance, facing_z):
    assert CotStrategy(max_tokens=2048).build(make_instance([facing_z()]), ImageStore()).generation.max_tokens == 2048


def test_spatial_cot_differs_from_cot_only_in_step4(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    cot, scot = CotStrategy().prompt_text(inst), SpatialCotStrategy().prompt_text(inst)
    assert scot == cot.replace(load_template("cot_step4"), load_template("spatial_cot_step4"))
    assert "4e) Target coordinate estimation." in scot and "4a)" not in cot


def test_given_instances_get_the_basic_given_prompt(make_instance, facing_z):
    inst = make_instance([facing_z()], condition=Condition.GIVEN)
    assert SpatialCotStrategy().prompt_text(inst) == BasicStrategy().prompt_text(inst)


def test_cot_message_layout_is_the_basic_one(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    store = ImageStore()
    basic = BasicStrategy().build(inst, store).messages[0].parts
    cot = CotStrategy().build(inst, store).messages[0].parts
    assert basic[:-1] == cot[:-1]

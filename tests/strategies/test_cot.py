"""The CoT and Spatial-CoT strategies (plugins/strategies/cot.py)."""

from __future__ import annotations

import pytest

from povagent.dataset.release_models import Condition
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


@pytest.mark.parametrize("prompts", ["runner", "appendix"])
def test_spatial_cot_differs_from_cot_only_in_step4(make_instance, facing_z, prompts):
    inst = make_instance([facing_z(), facing_z(90)])
    cot, scot = CotStrategy(prompts=prompts).prompt_text(inst), SpatialCotStrategy(prompts=prompts).prompt_text(inst)
    step4 = "cot_step4" if prompts == "runner" else "appendix_cot_step4"
    assert scot == cot.replace(load_template(step4), load_template(f"{step4.removesuffix('cot_step4')}spatial_cot_step4"))
    assert "4e) Target" in scot and "4a)" not in cot


def test_cot_strategies_show_the_first_30_frames_and_ask_for_one_of_them(make_instance, facing_z):
    inst = make_instance([facing_z(yaw) for yaw in range(0, 350, 10)])  # 35 frames
    request = SpatialCotStrategy().build(inst, ImageStore())
    assert len(request.image_hashes()) == 30 and request.answer.n_frames == 30


@pytest.mark.parametrize("prompts", ["molmopoint", "robopoint"])
def test_model_prompt_families_have_no_cot(prompts):
    with pytest.raises(ValueError, match="no chain-of-thought prompt"):
        CotStrategy(prompts=prompts)


def test_cot_on_given_is_outside_the_papers_protocol(make_instance, facing_z):
    given = make_instance([facing_z()], condition=Condition.GIVEN)
    inferred = make_instance([facing_z()])
    assert CotStrategy().outside_paper_protocol(given) and not CotStrategy().outside_paper_protocol(inferred)
    assert not BasicStrategy().outside_paper_protocol(given)


def test_given_instances_get_the_basic_given_prompt(make_instance, facing_z):
    inst = make_instance([facing_z()], condition=Condition.GIVEN)
    assert SpatialCotStrategy().prompt_text(inst) == BasicStrategy().prompt_text(inst)


def test_cot_message_layout_is_the_basic_one(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    store = ImageStore()
    basic = BasicStrategy().build(inst, store).messages[0].parts
    cot = CotStrategy().build(inst, store).messages[0].parts
    assert basic[:-1] == cot[:-1]

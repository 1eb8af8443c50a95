"""The basic strategy and the paper's message layout (plugins/strategies/basic.py, layout.py)."""

from __future__ import annotations

import asyncio

import pytest

from povagent.dataset.release_models import Condition
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Response, TextPart
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.choice import ChoiceStrategy
from povagent_plugins.strategies.geometric import GeometricStrategy


def test_each_frame_is_preceded_by_its_image_label(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90), facing_z(180)])
    request = BasicStrategy().build(inst, ImageStore())
    (message,) = request.messages
    parts = message.parts
    assert message.role == "user"
    assert [p.text for p in parts[0:6:2]] == ["Image 0:", "Image 1:", "Image 2:"]
    assert all(isinstance(p, ImagePart) for p in parts[1:6:2])
    assert isinstance(parts[-1], TextPart) and parts[-1].text.startswith("You are the intelligent brain system")
    assert len(parts) == 7


def test_given_shows_the_label_image_then_the_observer_view_then_the_prompt(make_instance, facing_z):
    inst = make_instance([facing_z()], condition=Condition.GIVEN)
    parts = BasicStrategy().build(inst, ImageStore()).messages[0].parts
    assert isinstance(parts[0], TextPart) and parts[0].text == "Image:"  # the runner's label
    assert isinstance(parts[1], ImagePart)
    assert isinstance(parts[2], TextPart) and "The image provided shows the target scene" in parts[2].text
    assert len(parts) == 3


def test_basic_shows_every_frame_and_asks_for_one_of_them(make_instance, facing_z):
    inst = make_instance([facing_z()] * 33)
    request = BasicStrategy().build(inst, ImageStore())
    assert len(request.image_hashes()) == 33 and request.answer.n_frames == 33


def test_max_frames_keeps_the_first_frames_and_the_answer_spec_follows(make_instance, facing_z):
    inst = make_instance([facing_z(yaw) for yaw in range(0, 350, 10)])  # 35 frames
    store = ImageStore()
    request = BasicStrategy(max_frames=30).build(inst, store)
    assert request.image_hashes() == [store.add_file(f.file).image_hash for f in inst.frames[:30]]
    assert request.answer.n_frames == 30 and request.answer.json_schema["properties"]["selected_image"]["maximum"] == 29


def test_no_token_limit_sends_no_max_tokens(make_instance, facing_z):
    request = BasicStrategy(max_tokens=None).build(make_instance([facing_z()]), ImageStore())
    assert request.generation.max_tokens is None and "max_tokens" not in request.generation.as_dict()


def test_images_are_referenced_by_the_hash_of_their_file(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    store = ImageStore()
    request = BasicStrategy().build(inst, store)
    assert request.image_hashes() == [store.add_file(f.file).image_hash for f in inst.frames]


def test_frames_answer_schema_asks_for_a_frame_among_those_shown(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90), facing_z(180)])
    spec = BasicStrategy().build(inst, ImageStore()).answer
    assert spec.asks_frame and spec.n_frames == 3 and (spec.width, spec.height) == (512, 512)
    assert spec.required_keys == ("selected_image", "x", "y")
    assert spec.json_schema["properties"]["selected_image"]["maximum"] == 2
    assert spec.json_schema["properties"]["x"]["maximum"] == 511


def test_given_answer_schema_asks_for_a_point_only(make_instance, facing_z):
    spec = BasicStrategy().build(make_instance([facing_z()], condition=Condition.GIVEN), ImageStore()).answer
    assert not spec.asks_frame and spec.required_keys == ("x", "y")


def test_answer_spec_without_building_matches_the_request(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    strategy = BasicStrategy()
    assert strategy.answer_spec(inst) == strategy.build(inst, ImageStore()).answer


def test_basic_asks_for_256_new_tokens_by_default(make_instance, facing_z):
    request = BasicStrategy().build(make_instance([facing_z()]), ImageStore())
    assert request.generation.max_tokens == 256 and request.generation.temperature is None


def test_generation_options_are_configurable(make_instance, facing_z):
    request = BasicStrategy(max_tokens=64, temperature=0).build(make_instance([facing_z()]), ImageStore())
    assert request.generation.as_dict() == {"max_tokens": 64, "temperature": 0.0}


@pytest.mark.parametrize(
    "options", [{"max_tokens": 0}, {"max_tokens": "many"}, {"temperature": -1}, {"max_frames": 0}, {"prompts": "papers"}]
)
def test_bad_generation_options_are_rejected_with_the_option_named(options):
    with pytest.raises(ValueError, match=next(iter(options))):
        BasicStrategy(**options)


@pytest.mark.parametrize("strategy", [BasicStrategy, ChoiceStrategy, GeometricStrategy])
@pytest.mark.parametrize("temperature", [-1, True, "warm"])
def test_every_strategy_refuses_a_temperature_that_is_not_a_number_at_least_0(strategy, temperature):
    with pytest.raises(ValueError, match="strategy option temperature must be a number >= 0"):
        strategy(temperature=temperature)


def test_the_built_in_strategy_is_single_turn(make_instance, facing_z):
    inst = make_instance([facing_z()])
    asked = []

    async def ask(request):
        asked.append(request)
        return Response(text='{"selected_image": 0, "x": 1, "y": 2}')

    exchanges = asyncio.run(BasicStrategy().solve(inst, ask, ImageStore()))
    assert len(asked) == 1 and len(exchanges) == 1 and exchanges[0][1].text.startswith("{")


def test_the_request_hash_is_stable_across_stores(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(90)])
    assert BasicStrategy().build(inst, ImageStore()).content_hash() == BasicStrategy().build(inst, ImageStore()).content_hash()


# -- messages and prompts built once per frame set / template, the same values -------------------
from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema  # noqa: E402
from povagent.exchange.messages import Message, Request  # noqa: E402
from povagent.exchange.prompts import frame_values, render  # noqa: E402
from povagent_plugins.strategies.basic import fill_sentence  # noqa: E402
from povagent_plugins.strategies.layout import answer_spec, prompt_message  # noqa: E402


def _message_part_by_part(instance, hashes, text):
    """The layout as first written: every part built afresh."""
    parts = []
    if instance.condition.uses_exploration_frames:
        for i, h in enumerate(hashes):
            parts.append(TextPart(f"Image {i}:"))
            parts.append(ImagePart(h, label=f"Image {i}"))
    else:
        parts.append(TextPart("Image:"))
        parts.extend(ImagePart(h, label="observer view") for h in hashes)
    parts.append(TextPart(text))
    return Message("user", tuple(parts))


@pytest.mark.parametrize("condition", [Condition.INFERRED, Condition.STATED, Condition.GIVEN])
def test_shared_message_parts_give_the_same_message(make_instance, facing_z, condition):
    inst = make_instance([facing_z(), facing_z(90), facing_z(180)], condition=condition)
    for hashes in (["a" * 64, "b" * 64, "c" * 64], ["c" * 64, "b" * 64, "a" * 64], ["a" * 64], ["a" * 64, "b" * 64, "c" * 64]):
        for text in ("first prompt", "second prompt"):
            assert prompt_message(inst, hashes, text) == _message_part_by_part(inst, hashes, text)


@pytest.mark.parametrize("condition", [Condition.INFERRED, Condition.GIVEN])
def test_built_requests_hash_as_when_built_part_by_part(make_instance, facing_z, condition):
    inst = make_instance([facing_z(), facing_z(90)], condition=condition)
    store = ImageStore()
    strategy = BasicStrategy()
    built = strategy.build(inst, store)
    hashes = [store.add_file(f.file).image_hash for f in inst.frames]
    width, height = inst.frame_size
    if condition.uses_exploration_frames:
        text = render("basic_frames", sentence=inst.sentence, **frame_values(width, height, len(inst.frames)))
        spec = AnswerSpec(schema=frame_answer_schema(len(inst.frames), width, height), width=width, height=height,
                          n_frames=len(inst.frames), asks_frame=True)
    else:
        text = render("basic_given", sentence=inst.sentence, **frame_values(width, height))
        spec = AnswerSpec(schema=point_answer_schema(width, height), width=width, height=height, n_frames=1, asks_frame=False)
    reference = Request(messages=(_message_part_by_part(inst, hashes, text),), answer=spec, generation=strategy.generation)
    assert built == reference and built.content_hash() == reference.content_hash()
    assert strategy.build(inst, store) == built  # and again, from the shared parts


@pytest.mark.parametrize("sentence", [
    "I saw it left of the desk.", "costs $5 or ${width}", "$sentence and ${sentence}", "$$ twice $$", "ünïcödé — ∈ ×",
    "a\x00povagent-sentence\x00b", "",
])
@pytest.mark.parametrize("name, n_images", [("basic_frames", 30), ("basic_frames", 1), ("basic_given", None)])
def test_prompt_filled_once_per_size_is_the_rendered_template(sentence, name, n_images):
    for width, height in ((512, 512), (640, 480)):
        expected = render(name, sentence=sentence, **frame_values(width, height, n_images))
        assert fill_sentence(name, sentence, width, height, n_images) == expected


def test_answer_specs_are_shared_and_equal_to_fresh_ones(make_instance, facing_z):
    a = make_instance([facing_z(), facing_z(90)])
    b = make_instance([facing_z(45), facing_z(135)], condition=Condition.STATED)
    c = make_instance([facing_z()], condition=Condition.GIVEN)
    assert answer_spec(a) is answer_spec(b)
    assert answer_spec(a) == AnswerSpec(schema=frame_answer_schema(2, 512, 512), n_frames=2, asks_frame=True)
    assert answer_spec(c) == AnswerSpec(schema=point_answer_schema(512, 512), n_frames=1, asks_frame=False)
    assert answer_spec(make_instance([facing_z()] * 3)).n_frames == 3

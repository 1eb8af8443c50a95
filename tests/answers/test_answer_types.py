"""Answer types are registered (``register_answer_types``): ``point`` by its built-in plugin
module exactly as a third party's type is, a name belongs to one plugin, and a type says what a
parse's value is, how the gold value is read and how a row shows a value."""

from __future__ import annotations

import pytest

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer, ParseStatus, unparseable
from povagent.answers.types import AnswerType
from povagent.errors import PluginError
from povagent.plugins import build_plugin_host

BOX = AnswerType(
    name="box", description="a box around the target", value_schema={"type": "object"},
    value_of=lambda parse: None, gold=lambda instance: None, show=lambda value: str(value.get("box")),
)  # fmt: skip


class BoxPlugin:
    @hookimpl
    def register_answer_types(self, register):
        register("box", BOX, description="test: a box")


class PointAgainPlugin:
    @hookimpl
    def register_answer_types(self, register):
        register("point", BOX)


def test_point_is_registered_by_its_built_in_plugin_module():
    host = build_plugin_host()
    assert host.entry("answer_type", "point").source == "built-in povagent_plugins.answers.point"
    assert host.answer_type("point").name == "point"


def test_a_third_party_answer_type_is_registered_beside_point(povagent_host):
    povagent_host.add_plugin(BoxPlugin(), name="box-plugin")
    try:
        assert povagent_host.names("answer_type") == ["box", "choice", "choice-or-number", "number", "point", "walk"]
        assert povagent_host.answer_type("box") is BOX
    finally:
        povagent_host.remove_plugin("box-plugin")


def test_an_answer_type_registered_twice_names_both_plugins(povagent_host):
    povagent_host.add_plugin(PointAgainPlugin(), name="again", source="plugin again")
    try:
        with pytest.raises(PluginError, match=r"answer_type name 'point' is registered twice") as err:
            povagent_host.names("answer_type")
        assert "built-in povagent_plugins.answers.point" in str(err.value) and "plugin again" in str(err.value)
    finally:
        povagent_host.remove_plugin("again")


def test_a_point_value_is_the_frame_and_the_pixel_of_an_answer():
    point = build_plugin_host().answer_type("point")
    parse = ParsedAnswer(status=ParseStatus.OK, selected_image=2, x=10.0, y=20.5)
    assert point.value_of(parse) == {"selected_image": 2, "x": 10.0, "y": 20.5}
    assert point.show(point.value_of(parse)) == "(10.0, 20.5) in frame 2"
    assert point.value_of(unparseable("no JSON")) is None


def test_the_gold_point_is_the_targets_position(mini_root):
    from povagent.dataset.loader import load_dataset

    instance = next(iter(load_dataset(mini_root, check_images=False).instances()))
    assert build_plugin_host().answer_type("point").gold(instance) == [float(v) for v in instance.target]

"""A tool call is read into the registered tool and its typed arguments, or into an invalid call
saying why: never an exception."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from povagent.active.tools import InvalidCall, ToolSet, read_call
from povagent.plugins import get_plugin_host
from povagent_plugins.tools.answer import Answer
from povagent_plugins.tools.go_to_frame import GoToFrame
from povagent_plugins.tools.move import Move
from povagent_plugins.tools.tilt import Tilt
from povagent_plugins.tools.turn import Turn


def test_the_registry_offers_exactly_the_six_built_in_tools_by_their_names():
    tools = get_plugin_host().tools()
    assert tools.names == ("go_to_frame", "turn", "tilt", "move", "ask", "answer")
    assert all(t["type"] == "function" and t["function"]["parameters"]["additionalProperties"] is False for t in tools.schemas())


def test_each_task_offers_its_own_tools_and_a_tool_for_every_task_is_offered_by_all():
    every = get_plugin_host().tools(None)
    assert every.names == ("go_to_frame", "turn", "tilt", "move", "ask", "answer", "arrived")
    assert every.for_task("navigate").names == ("turn", "tilt", "move", "ask", "arrived")
    zoom = ToolSet([("zoom", replace(every["turn"], tasks=None)), *every.tools.items()])
    assert zoom.for_task("point").names[0] == zoom.for_task("navigate").names[0] == "zoom"


def test_the_arrived_call_takes_no_arguments_and_ends_the_episode():
    tools = get_plugin_host().tools("navigate")
    tool, typed = read_call("arrived", "{}", tools)
    assert tool.ends and typed is None
    assert read_call("arrived", '{"here": true}', tools) == InvalidCall("arrived: unexpected here (takes nothing)")
    assert isinstance(read_call("arrived", "{}", get_plugin_host().tools()), InvalidCall)  # the point task has no arrived


@pytest.mark.parametrize(
    ("name", "arguments", "action"),
    [
        ("go_to_frame", {"frame": 3}, GoToFrame(3)),
        ("go_to_frame", {"frame": 3.0}, GoToFrame(3)),
        ("turn", {"degrees": -45}, Turn(-45.0)),
        ("tilt", {"degrees": 12.5}, Tilt(12.5)),
        ("move", {"forward": 1, "right": -0.5}, Move(1.0, -0.5)),
        ("answer", {"image": "View 2", "x": 10, "y": 20.5}, Answer("view", 2, 10.0, 20.5)),
        ("answer", {"image": "frame 0", "x": 0, "y": 0}, Answer("frame", 0, 0.0, 0.0)),
    ],
)
def test_a_well_formed_call_becomes_its_typed_action(name, arguments, action):
    tool, typed = read_call(name, json.dumps(arguments), get_plugin_host().tools())
    assert tool is get_plugin_host().tools()[name] and typed == action


@pytest.mark.parametrize(
    ("name", "arguments", "why"),
    [
        ("fly", "{}", "unknown tool 'fly'"),
        ("turn", "{}", "missing degrees"),
        ("turn", '{"degrees": 1, "speed": 2}', "unexpected speed"),
        ("turn", '{"degrees": "90"}', "must be a number, got str"),
        ("turn", '{"degrees": true}', "must be a number, got bool"),
        ("turn", '{"degrees": NaN}', "finite"),
        ("tilt", '{"degrees": Infinity}', "finite"),
        ("move", '{"forward": 1e308, "right": 0}', "within"),
        ("move", '{"forward": 1e999, "right": 0}', "finite"),
        ("go_to_frame", '{"frame": "2"}', "must be an integer"),
        ("go_to_frame", '{"frame": 1.5}', "must be an integer"),
        ("answer", '{"image": "picture 2", "x": 1, "y": 2}', '"frame k" or "view n"'),
        ("answer", '{"image": "view 1", "x": NaN, "y": 2}', "finite"),
        ("ask", '{"question": 42}', "must be a string"),
        ("ask", json.dumps({"question": "x" * 600}), "longer than"),
        ("turn", "not json", "not a JSON object"),
        ("turn", "[1, 2]", "not a JSON object"),
        ("turn", "[" * 5000, "longer than"),
    ],
)
def test_a_hostile_call_becomes_an_invalid_call_naming_the_problem(name, arguments, why):
    result = read_call(name, arguments, get_plugin_host().tools())
    assert isinstance(result, InvalidCall)
    assert why in result.reason


@pytest.mark.parametrize(("name", "field"), [("turn", "degrees"), ("tilt", "degrees"), ("move", "forward"), ("answer", "x")])
def test_an_integer_too_large_for_a_float_is_an_invalid_call_naming_its_length(name, field):
    arguments = {"turn": {"degrees": 0}, "tilt": {"degrees": 0}, "move": {"forward": 0, "right": 0},
                 "answer": {"image": "view 1", "x": 0, "y": 0}}[name]  # fmt: skip
    text = json.dumps(arguments).replace(f'"{field}": 0', f'"{field}": {"9" * 400}')
    result = read_call(name, text, get_plugin_host().tools())
    assert isinstance(result, InvalidCall) and "an integer of 400 digits" in result.reason

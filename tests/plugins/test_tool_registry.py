"""The plugin host owns the names of active-mode tools as it owns every other name: the tools
come in the order their plugins were loaded (the built-ins first), and a name registered twice,
or something registered that is not a tool, is one error naming the plugin."""

from __future__ import annotations

import pytest

from povagent import hookimpl
from povagent.errors import PluginError
from povagent_plugins.tools.turn import TOOL as TURN


def _tool_plugin(name: str, tool: object = TURN):
    class Plugin:
        @hookimpl
        def register_tools(self, register):
            register(name, tool)

    return Plugin()


def test_the_built_in_tools_are_registered_in_the_order_they_are_offered(povagent_host):
    assert povagent_host.tools().names == ("go_to_frame", "turn", "tilt", "move", "ask", "answer")


def test_a_plugin_tool_comes_after_the_built_ins(povagent_host):
    povagent_host.add_plugin(_tool_plugin("spin"), name="spin-plugin")
    assert povagent_host.tools().names[-2:] == ("answer", "spin")


def test_a_tool_name_registered_twice_is_an_error_naming_both_plugins(povagent_host):
    povagent_host.add_plugin(_tool_plugin("turn"), name="second-turn", source="plugin second-turn")
    with pytest.raises(PluginError, match=r"tool name 'turn' is registered twice: by built-in povagent_plugins.tools.turn and by plugin second-turn"):
        povagent_host.tools()


def test_something_registered_that_is_not_a_tool_is_an_error_naming_the_plugin(povagent_host):
    povagent_host.add_plugin(_tool_plugin("spin", {"name": "spin"}), name="dict-tool", source="plugin dict-tool")
    with pytest.raises(PluginError, match=r"plugin dict-tool: tool 'spin' is a dict, not a povagent.active.tools.Tool"):
        povagent_host.tools()


def test_a_tool_name_function_calling_cannot_carry_is_an_error_naming_the_plugin(povagent_host):
    povagent_host.add_plugin(_tool_plugin("look around"), name="spaced", source="plugin spaced")
    with pytest.raises(PluginError, match=r"plugin spaced: registered a tool with an invalid name 'look around'"):
        povagent_host.tools()


def test_the_plugins_command_lists_each_tool_with_its_source_in_the_order_offered():
    import json

    from typer.testing import CliRunner

    from povagent.cli import app

    result = CliRunner().invoke(app, ["plugins", "--json"])
    assert result.exit_code == 0, result.output
    tools = json.loads(result.output)["tool"]
    assert [t["name"] for t in tools] == ["go_to_frame", "turn", "tilt", "move", "ask", "answer", "arrived"]
    assert tools[1]["source"] == "built-in povagent_plugins.tools.turn" and tools[1]["description"].startswith("Rotate in place")

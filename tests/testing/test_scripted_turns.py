"""A model's turns from a file, replayed by the loopback server (povagent/testing/scripted_turns.py):
texts and tool calls in order, then the fixed reply; a malformed file is one line naming the
file, the line and the field."""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.request

import pytest

from povagent.errors import ConfigError
from povagent.testing.loopback_server import LoopbackServer
from povagent.testing.scripted_turns import Turn, read_turns

pytestmark = pytest.mark.timeout(60)

TURNS_YAML = """\
- tool_calls:
    - {name: go_to_frame, arguments: {frame: 1}}
    - {name: tilt, arguments: '{"degrees": NaN}'}
- '{"selected_image": 0, "x": 1, "y": 2}'
- text: thinking
  tool_calls: [{name: answer, arguments: {image: view 1, x: 3.5, y: 4}}]
"""


def post(url: str) -> dict:
    body = json.dumps({"model": "m", "messages": [{"role": "user", "content": "hi"}]}).encode()
    request = urllib.request.Request(f"{url}/chat/completions", data=body, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=20) as response:
        return json.load(response)["choices"][0]


def calls_of(choice: dict) -> list[tuple[str, str]]:
    return [(c["function"]["name"], c["function"]["arguments"]) for c in choice["message"].get("tool_calls", [])]


def test_the_turns_of_a_file_answer_the_first_requests_in_order_then_the_fixed_reply(tmp_path):
    (tmp_path / "turns.yaml").write_text(TURNS_YAML)
    with LoopbackServer(reply="fixed") as server:
        server.script(read_turns(tmp_path / "turns.yaml"))
        first, second, third, fourth = (post(server.url) for _ in range(4))
    assert first["finish_reason"] == "tool_calls" and first["message"]["content"] is None
    assert calls_of(first) == [("go_to_frame", '{"frame": 1}'), ("tilt", '{"degrees": NaN}')]  # a text: sent as written
    assert second["message"]["content"] == '{"selected_image": 0, "x": 1, "y": 2}' and calls_of(second) == []
    assert third["message"]["content"] == "thinking"
    assert calls_of(third) == [("answer", '{"image": "view 1", "x": 3.5, "y": 4}')]
    assert fourth["message"]["content"] == "fixed"


def test_a_json_file_reads_as_the_same_turns(tmp_path):
    (tmp_path / "turns.yaml").write_text(TURNS_YAML)
    import yaml

    (tmp_path / "turns.json").write_text(json.dumps(yaml.safe_load(TURNS_YAML)))
    assert read_turns(tmp_path / "turns.json") == read_turns(tmp_path / "turns.yaml")
    assert read_turns(tmp_path / "turns.json")[1] == Turn('{"selected_image": 0, "x": 1, "y": 2}')


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{tool_calls: []}", r"turns\.yaml: a turns file is a list of turns"),
        ("- 7", r"turns\.yaml, line 1: turn 1: a turn is a text or a mapping"),
        ("- ok\n- {tool_calls: [{name: turn, arguments: {degrees: 1}}], say: hi}", r"line 2: turn 2, field say: unknown key"),
        ("- tool_calls:\n    - {name: turn}\n    - {arguments: {degrees: 1}}", r"line 3: turn 1, field tool_calls\[1\]\.name: the tool's name is required"),
        ("- tool_calls: [{name: turn, arguments: [1, 2]}]", r"turn 1, field tool_calls\[0\]\.arguments: a mapping, or a text"),
        ("- tool_calls: [{name: ask, arguments: {question: 2024-01-01}}]", r"field tool_calls\[0\]\.arguments: holds a value JSON cannot carry"),
        ("- {text: null}", r"turn 1: a turn needs a text or at least one tool call"),
        ("- tool_calls: [{name: turn, arguments: {}}, oops", r"turns\.yaml, line 1: not valid YAML"),
    ],
)  # fmt: skip
def test_a_malformed_turns_file_is_one_line_naming_the_file_the_line_and_the_field(tmp_path, text, message):
    (tmp_path / "turns.yaml").write_text(text)
    with pytest.raises(ConfigError, match=message) as caught:
        read_turns(tmp_path / "turns.yaml")
    assert "\n" not in str(caught.value)


def test_aliases_that_expand_a_file_beyond_bounds_are_refused_before_they_expand(tmp_path):
    bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n" for p, c in zip("abcdef", "bcdefg")
    )
    (tmp_path / "turns.yaml").write_text(bomb)
    with pytest.raises(ConfigError, match="aliases"):
        read_turns(tmp_path / "turns.yaml")


def test_the_command_line_server_refuses_a_malformed_script_at_start_in_one_line(tmp_path):
    (tmp_path / "turns.yaml").write_text("- tool_calls: [{name: 3}]\n")
    done = subprocess.run(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--port", "0", "--lifetime", "5",
         "--script", str(tmp_path / "turns.yaml")],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 2 and done.stdout == "" and "Traceback" not in done.stderr
    assert "--script" in done.stderr and "turns.yaml, line 1: turn 1, field tool_calls[0].name" in done.stderr

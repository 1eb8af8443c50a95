"""``povagent parse``: one raw answer on stdin, its typed parse as JSON on stdout."""

from __future__ import annotations

import json

import pytest
from console_once import console_script_once
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import ConfigError, PluginError

runner = CliRunner()


def parse(text: str, *args: str) -> dict:
    result = runner.invoke(app, ["parse", *args], input=text)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_prints_the_typed_parse_with_the_documented_keys():
    out = parse('```json\n{"selected_image": 4, "x": 250, "y": 310}\n```', "--parser", "json")
    assert {"status", "reason", "selected_image", "x", "y"} <= set(out)
    assert (out["status"], out["selected_image"], out["x"], out["y"]) == ("ok", 4, 250.0, 310.0)


def test_condition_c_asks_for_a_point_only():
    out = parse('{"x": 20, "y": 30}', "--parser", "json", "--condition", "c")
    assert (out["status"], out["selected_image"], out["x"]) == ("ok", None, 20.0)


def test_the_frame_count_bounds_selected_image():
    out = parse('{"selected_image": 5, "x": 1, "y": 1}', "--frames", "5")
    assert out["status"] == "out_of_range" and "selected_image=5 outside [0, 4]" in out["reason"]


def test_width_and_height_set_the_pixel_range():
    out = parse('{"x": 600, "y": 10}', "--condition", "given", "--width", "640", "--height", "480")
    assert out["status"] == "ok"


def test_native_parsers_convert_to_pixels_of_the_requested_size():
    out = parse('[{"point": [500, 250]}]', "--parser", "gemini", "--condition", "c", "--width", "1000", "--height", "800")
    assert (out["x"], out["y"]) == (250.0, 400.0)


def test_a_repair_is_reported():
    out = parse('{"selected_image": 1, "x": 734, "y": 402}', "--parser", "rescale-1000")
    assert out["status"] == "repaired" and out["repair"] == "rescaled 0-1000 -> pixels"


def test_an_unparseable_answer_says_why():
    out = parse("I cannot tell.", "--parser", "json")
    assert out["status"] == "unparseable" and out["reason"] and out["x"] is None


def test_an_unknown_parser_is_a_clear_error():
    result = runner.invoke(app, ["parse", "--parser", "jsn"], input="{}")
    assert isinstance(result.exception, PluginError) and "did you mean 'json'" in str(result.exception)


def test_an_unknown_condition_is_a_clear_error():
    result = runner.invoke(app, ["parse", "--condition", "d"], input="{}")
    assert isinstance(result.exception, ConfigError) and "--condition" in str(result.exception)


def test_the_console_script_reads_stdin(tmp_path_factory, mini_root):
    # its input, console_once.PARSE_INPUT: <point x="50" y="25" alt="cup">cup</point>
    proc = console_script_once(tmp_path_factory, mini_root)["parse"]
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["y"] == pytest.approx(128.0)
